#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The 2015 Hector + graph / particle-filter pipeline against the methods with wheel odometry
(issue 24's figures; R. Kaijaluoto, A. Kukko, J. Hyyppa, "Precise indoor localization for mobile
laser scanner", ISPRS Archives XL-4/W5, 2015).

For each log (intel, aces, fr079) this runs, all with --trajectory-frame sensor (what the relations
describe):
  with wheel odometry      slam2d map LOG --method graph | rbpf (seeds 1..N) | hector
  without wheel odometry   slam2d map LOG --method hector --odometry-source none
                           slam2d map LOG --method graph --odometry-source none
                           slam2d map LOG --method graph --odometry-source hector      (every scan)
                           slam2d map LOG --method hector+graph                        (the chain)
                           slam2d map LOG --method hector+rbpf --seed S                (the chain)
and reports the mean translational relation error (slam2d eval --relations) of each. For the two
chains it also reports, as the issue asks:
  - the sparse trajectory (sparse_trajectory.txt, 3 scans a second) on the relations it covers,
    the fused one on those same relations and on all of them, and the sparse one densified by
    linear interpolation at every scan (what fusion must beat to be worth it);
  - the relation error of the fused trajectory and of Hector's on the relations spanning at most
    1 s (the true error at the shortest scale the logs' relations have: Intel 365, ACES 1059,
    FR079 741 of them, FR079's all 0.5-1 s), and the paired difference fused - Hector over those
    relations (mean and its standard error: is the fused trajectory locally worse than Hector's?);
  - the 0.2 s RPE (slam2d eval --reference REF --rpe-window time --rpe-delta 0.2) of the fused
    trajectory and of Hector's dense one. No log has a dense ground truth, so REF is graph SLAM
    with wheel odometry on every scan, the most accurate dense trajectory we have (its relation
    error is in the first row); an RPE against it measures agreement with it, not truth. So the
    same RPE is also given against a second, independent reference, the median RBPF run with
    wheel odometry (every scan).
RBPF figures are the median over the seeds (its spread on ACES is wide, docs/bags.md). Each log's
runs (the median seed of the seeded ones) also go into one HTML report (slam2d report,
docs/report.md): OUT/LOG-report/index.html.

Usage: bench/datasets/pipeline_benchmark.py [--slam2d build/release/bin/slam2d] [--data /work/shared/data]
                                            [--seeds 3] [--logs intel aces fr079] [--out /tmp/slam2d_pipeline] [--json]
"""

import argparse
import bisect
import csv
import json
import math
import os
import sys

from common import run_json, read_trajectory, write_atomic, write_report

LOGS = ["intel", "aces", "fr079"]
TOLERANCE = 0.001  # s, slam2d eval's default stamp tolerance
SHORT_SPAN = 1.0  # s: the short relations, the true local error (FR079 has none under 0.5 s)


def write_trajectory(path, poses):
    write_atomic(path, "".join(f"{t:.6f} {x:.6f} {y:.6f} {theta:.6f}\n" for t, x, y, theta in poses))


def densified(sparse, stamps):
    """The sparse poses linearly interpolated (heading unwrapped) at the stamps within their span."""
    sparse = sorted(sparse)
    unwrapped = [sparse[0][3]]
    for p in sparse[1:]:
        unwrapped.append(unwrapped[-1] + math.remainder(p[3] - unwrapped[-1], 2 * math.pi))
    out, k = [], 0
    for t in sorted(stamps):
        if t < sparse[0][0] or t > sparse[-1][0]:
            continue
        while k + 1 < len(sparse) - 1 and sparse[k + 1][0] < t:
            k += 1
        a, b = sparse[k], sparse[min(k + 1, len(sparse) - 1)]
        s = 0.0 if b[0] == a[0] else (t - a[0]) / (b[0] - a[0])
        theta = unwrapped[k] + s * (unwrapped[min(k + 1, len(sparse) - 1)] - unwrapped[k])
        out.append((t, a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]), math.remainder(theta, 2 * math.pi)))
    return out


def filter_relations(relations_path, out_path, keep):
    """The relations file's lines for which keep(stamp_from, stamp_to) holds, written to out_path; how many."""
    kept = []
    with open(relations_path) as f:
        for line in f:
            fields = line.split()
            if len(fields) >= 2 and keep(float(fields[0]), float(fields[1])):
                kept.append(line)
    write_atomic(out_path, "".join(kept))
    return len(kept)


def covered_relations(relations_path, trajectory, out_path):
    """The relations both of whose stamps the trajectory has a pose for (within TOLERANCE)."""
    stamps = sorted(p[0] for p in trajectory)

    def has(t):
        i = bisect.bisect_left(stamps, t)
        return any(0 <= j < len(stamps) and abs(stamps[j] - t) <= TOLERANCE for j in (i - 1, i))

    return filter_relations(relations_path, out_path, lambda a, b: has(a) and has(b))


def short_relations(relations_path, out_path, max_span=SHORT_SPAN):
    """The relations between two scans at most max_span s apart."""
    return filter_relations(relations_path, out_path, lambda a, b: abs(b - a) <= max_span)


def paired_difference(errors_a, errors_b):
    """Mean and standard error of (a - b) over the relations both CSVs (slam2d eval --errors-csv) hold."""
    def load(path):
        with open(path) as f:
            return {(r["stamp_from"], r["stamp_to"]): float(r["translation_m"]) for r in csv.DictReader(f)}
    a, b = load(errors_a), load(errors_b)
    d = [a[k] - b[k] for k in a if k in b]
    if len(d) < 2:
        return {"mean": math.nan, "se": math.nan, "relations": len(d)}
    mean = sum(d) / len(d)
    sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (len(d) - 1))
    return {"mean": mean, "se": sd / math.sqrt(len(d)), "relations": len(d)}


class Bench:
    def __init__(self, args):
        self.args = args
        os.makedirs(args.out, exist_ok=True)

    def map(self, log, name, *options):
        out = os.path.join(self.args.out, f"{log}-{name}")
        log_path = os.path.join(self.args.data, log, f"{log}.clf.gz")
        summary = run_json([self.args.slam2d, "map", log_path, "--trajectory-frame", "sensor", "--out", out, "--quiet", "--json",
                            *options])
        return out, summary

    def relation_error(self, log, trajectory, relations=None, errors_csv=None):
        relations = relations or os.path.join(self.args.data, log, f"{log}.relations")
        extra = ["--errors-csv", errors_csv] if errors_csv else []
        result = run_json([self.args.slam2d, "eval", trajectory, "--relations", relations, "--json", *extra])
        return {"trans_mean": result["trans_mean"], "rot_mean_deg": result["rot_mean_deg"],
                "relations": result["relations"] - result["missing"]}

    def rpe(self, trajectory, reference):
        result = run_json([self.args.slam2d, "eval", trajectory, "--reference", reference, "--rpe-window", "time",
                           "--rpe-delta", "0.2", "--json"])
        return {"trans_mean": result["rpe_trans_mean"], "rot_mean_deg": result["rpe_rot_mean_deg"], "pairs": result["rpe_pairs"]}

    def method(self, log, name, *options):
        out, summary = self.map(log, name, *options)
        return {"error": self.relation_error(log, os.path.join(out, "trajectory.txt")), "cpu_s": summary["cpu_s"], "out": out,
                "summary": summary}

    def seeded(self, log, name, *options):
        runs = [self.method(log, f"{name}-s{seed}", "--seed", str(seed), *options) for seed in range(1, self.args.seeds + 1)]
        runs.sort(key=lambda r: r["error"]["trans_mean"])
        median = runs[len(runs) // 2]
        median["spread"] = [runs[0]["error"]["trans_mean"], runs[-1]["error"]["trans_mean"]]
        return median

    def chain(self, log, run, reference, second_reference):
        out = run["out"]
        fused = os.path.join(out, "trajectory.txt")
        sparse_path = os.path.join(out, "sparse_trajectory.txt")
        hector = os.path.join(out, "hector_trajectory.txt")
        sparse = read_trajectory(sparse_path)
        subset = os.path.join(out, "sparse_relations.txt")
        covered_relations(os.path.join(self.args.data, log, f"{log}.relations"), sparse, subset)
        dense_stamps = [p[0] for p in read_trajectory(fused)]
        short = os.path.join(out, "short_relations.txt")
        short_relations(os.path.join(self.args.data, log, f"{log}.relations"), short)
        naive = os.path.join(out, "sparse_densified.txt")
        write_trajectory(naive, densified(sparse, dense_stamps))
        return {
            "sparse_on_its_relations": self.relation_error(log, sparse_path, subset),
            "fused_on_sparse_relations": self.relation_error(log, fused, subset),
            "fused": self.relation_error(log, fused),
            "sparse_densified": self.relation_error(log, naive),
            "hector": self.relation_error(log, hector),
            "short_fused": self.relation_error(log, fused, short, os.path.join(out, "short_fused.csv")),
            "short_hector": self.relation_error(log, hector, short, os.path.join(out, "short_hector.csv")),
            "short_paired": paired_difference(os.path.join(out, "short_fused.csv"), os.path.join(out, "short_hector.csv")),
            "rpe_fused": self.rpe(fused, reference),
            "rpe_hector": self.rpe(hector, reference),
            "rpe2_fused": self.rpe(fused, second_reference),
            "rpe2_hector": self.rpe(hector, second_reference),
            "hector_jumps_smoothed": run["summary"]["chain"]["hector_jumps_smoothed"],
        }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--slam2d", default="build/release/bin/slam2d")
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--logs", nargs="+", default=LOGS)
    parser.add_argument("--out", default="/tmp/slam2d_pipeline")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    bench = Bench(args)
    results = {}
    for log in args.logs:
        print(f"{log} ...", file=sys.stderr, flush=True)
        r = {
            "graph": bench.method(log, "graph", "--method", "graph"),
            "rbpf": bench.seeded(log, "rbpf", "--method", "rbpf"),
            "hector": bench.method(log, "hector", "--method", "hector"),
            "hector_none": bench.method(log, "hector-none", "--method", "hector", "--odometry-source", "none"),
            "graph_none": bench.method(log, "graph-none", "--method", "graph", "--odometry-source", "none"),
            "graph_hector": bench.method(log, "graph-hector", "--method", "graph", "--odometry-source", "hector"),
            "hector+graph": bench.method(log, "hector+graph", "--method", "hector+graph"),
            "hector+rbpf": bench.seeded(log, "hector+rbpf", "--method", "hector+rbpf"),
        }
        reference = os.path.join(r["graph"]["out"], "trajectory.txt")  # graph SLAM with wheel odometry, every scan
        second_reference = os.path.join(r["rbpf"]["out"], "trajectory.txt")  # the median RBPF run with wheel odometry
        for name in ("hector+graph", "hector+rbpf"):
            r[name]["chain"] = bench.chain(log, r[name], reference, second_reference)
        results[log] = r
        page = write_report(args.slam2d, [run["out"] for run in r.values()], os.path.join(args.out, f"{log}-report"),
                            os.path.join(args.data, log, f"{log}.relations"), os.path.join(args.data, log, f"{log}.clf.gz"))
        print(f"report: {page}", file=sys.stderr, flush=True)

    rows = [("graph", "graph SLAM", "log"), ("rbpf", "RBPF (median)", "log"), ("hector", "Hector", "log"),
            ("hector_none", "Hector", "none"), ("graph_none", "graph SLAM", "none"),
            ("graph_hector", "graph SLAM, every scan", "hector"), ("hector+graph", "hector+graph (fused)", "hector"),
            ("hector+rbpf", "hector+rbpf (fused, median)", "hector")]
    print("| method | odometry | " + " | ".join(args.logs) + " |")
    print("|---|---|" + "---|" * len(args.logs))
    for key, label, odometry in rows:
        cells = []
        for log in args.logs:
            run = results[log][key]
            cell = f"{run['error']['trans_mean']:.4f} ({run['cpu_s']:.1f} s)"
            if "spread" in run:
                cell += f" [{run['spread'][0]:.4f}, {run['spread'][1]:.4f}]"
            cells.append(cell)
        print(f"| {label} | {odometry} | " + " | ".join(cells) + " |")
    print()
    print("| chain | log | sparse, its relations | fused, same relations | fused, all | sparse densified, all | "
          "Hector, all | relations <= 1 s: fused / Hector (n) | fused - Hector, mean ± s.e. (mm) | 0.2 s RPE fused | 0.2 s RPE Hector | 0.2 s RPE against RBPF: fused / Hector | jumps smoothed |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in ("hector+graph", "hector+rbpf"):
        for log in args.logs:
            c = results[log][name]["chain"]
            e = lambda k: f"{c[k]['trans_mean']:.4f}"
            print(f"| {name} | {log} | {e('sparse_on_its_relations')} ({c['sparse_on_its_relations']['relations']}) | "
                  f"{e('fused_on_sparse_relations')} | {e('fused')} ({c['fused']['relations']}) | {e('sparse_densified')} | "
                  f"{e('hector')} | {c['short_fused']['trans_mean']:.5f} / {c['short_hector']['trans_mean']:.5f} "
                  f"({c['short_fused']['relations']}) | {1e3 * c['short_paired']['mean']:+.2f} ± {1e3 * c['short_paired']['se']:.2f} | "
                  f"{c['rpe_fused']['trans_mean']:.6f} m, {c['rpe_fused']['rot_mean_deg']:.3f} deg | "
                  f"{c['rpe_hector']['trans_mean']:.6f} m, {c['rpe_hector']['rot_mean_deg']:.3f} deg | "
                  f"{c['rpe2_fused']['trans_mean']:.6f} / {c['rpe2_hector']['trans_mean']:.6f} m | "
                  f"{c['hector_jumps_smoothed']} |")
    if args.json:
        for log in results.values():
            for run in log.values():
                run.pop("summary", None)
        print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
