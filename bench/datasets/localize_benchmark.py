#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The localization comparison of Gutmann, Burgard, Fox, Konolige (IROS 1998) and Gutmann & Fox
(IROS 2002) on the public logs: every localizer of `slam2d localize` under added odometry noise,
a degraded scanner and a kidnap, over N seeds, scored against a graph-SLAM reference.

Per log (intel, aces, fr079):
1. Reference, made once and cached in OUT/reference/LOG: `slam2d map LOG --method graph`, whose
   map.yaml is the map to localize in and whose trajectory.txt (one pose per scan, the first at
   the origin) is the reference pose of every scan (0.018-0.037 m from the Kuemmerle 2009
   relations, bench/BENCHMARKS.md).
2. Conditions (CONDITIONS below), each with seeds 1..N: the log degraded by
       slam2d perturb LOG --out L --fault SPEC ... --seed S
   (odometry noise: `odom-noise` at 0, 1, 2, 4, 8 x BASE_NOISE, docs/faults.md; a scanner with range
   noise, with 1 beam in 8 kept, with spurious readings), or clean with a kidnap
       slam2d localize ... --kidnap-at T --kidnap-by 5,0,90
   (T = KIDNAP_AT of the run's duration + 10 (S - 1) s).
3. Each method (METHODS: markov, ekf, mcl without random samples, mcl with random samples
   (Gutmann & Fox 2002's injection, the default), hybrid) from the reference's first pose:
       slam2d localize L --map MAP --method M --initial x,y,th --seed S --out TRAJ --json --quiet
4. Per run, against the reference at the same scan (position error, m): mean and median error,
   the share of scans with an error above --threshold (1 m, the papers' "lost"), whether the run
   ends lost (every scan of its last 10 s above the threshold), with a kidnap the recovery time
   (s from the kidnap until the error is below the threshold and stays there for --hold s), and
   the localizer's CPU time per scan. A deterministic method (markov, ekf, hybrid) on the clean
   log runs once: its seeds would give the same run.

Outputs in --out (each written atomically): runs.csv (one row per run), summary.csv and
summary.md (one row per log, method, condition; the table of bench/BENCHMARKS.md), summary.json,
localize_noise.png (mean error and time lost against the odometry noise level, per method and
log). --json prints summary.json. A progress line on stderr unless --quiet.

Usage: /usr/bin/python3 bench/datasets/localize_benchmark.py [--slam2d build/release/bin/slam2d]
           [--data $SLAM2D_DATA] [--logs intel aces fr079] [--methods markov ekf mcl mcl-random hybrid]
           [--conditions ...] [--seeds 5] [--duration S] [--quick] [--jobs 1] [--threshold 1]
           [--hold 10] [--out /tmp/slam2d_localize_benchmark] [--resume] [--json] [--quiet]
--quick: 2 seeds and the first 300 s of each log (261 runs, 4.7 min with --jobs 1). `--seeds 3
--duration 600` (bench/BENCHMARKS.md) took 12.3 min; the full run, 5 seeds on the whole logs (2.8
times the data), about an hour with --jobs 1, half that with --jobs 2 (estimated from those).
--resume reuses the runs already in --out.
"""

import argparse
import csv
import io
import gzip
import json
import math
import os
import statistics
import sys
import tempfile
import threading
import time
import concurrent.futures

from common import fmt, read_trajectory, run, write_atomic

LOGS = {"intel": "intel/intel.clf.gz", "aces": "aces/aces.clf.gz", "fr079": "fr079/fr079.clf.gz"}

# name -> extra `slam2d localize` arguments; "@PLAIN_MCL" is replaced by a config turning the
# random-sample injection off.
METHODS = {
    "markov": ["--method", "markov"],
    "ekf": ["--method", "ekf"],
    "mcl": ["--method", "mcl", "--config", "@PLAIN_MCL"],
    "mcl-random": ["--method", "mcl"],
    "hybrid": ["--method", "hybrid"],
}
RANDOM_METHODS = {"mcl", "mcl-random"}  # draw from --seed; the others are deterministic

# The 1x odometry noise (odom-noise keys, docs/faults.md): a random walk of 10 cm along-track error
# and 2.3 deg of heading per sqrt(m) driven, and 5.7 deg of heading per sqrt(rad) turned. Picked on
# the first 300 s of Intel (seed 1): at 8x the EKF and MCL lose the robot, the Markov grid does not;
# at 4x every method still tracks.
BASE_NOISE = {"translation": 0.1, "heading": 0.04, "rotation": 0.1}
NOISE_LEVELS = [0, 1, 2, 4, 8]


def noise_spec(level):
    return "odom-noise:" + ",".join(f"{k}={v * level:g}" for k, v in BASE_NOISE.items())


# name -> (group, noise level or None, fault specs, kidnap)
CONDITIONS = {
    **{f"odom-x{n}": ("odometry", n, [noise_spec(n)] if n else [], False) for n in NOISE_LEVELS},
    "range-noise": ("sensor", None, ["range-noise:sigma=0.1"], False),
    "beams-1-in-8": ("sensor", None, ["beams:k=8"], False),
    "spurious": ("sensor", None, ["spurious-short:p=0.1", "spurious-max:p=0.1"], False),
    "kidnap": ("kidnap", None, [], True),
}
KIDNAP_AT = 1.0 / 3.0  # of the run's duration, + 10 s per seed
KIDNAP_BY = "5,0,90"   # m, m, deg in the robot frame
ENDS_LOST_S = 10.0     # a run ends lost when every scan of its last this many s is above the threshold


# ---------------------------------------------------------------------------------------------
# Metrics (python/tests/test_localize_benchmark.py).

def position_errors(trajectory, reference):
    """m, per scan: |p - p_ref| of rows (t, x, y, theta) matched scan by scan (trajectory may be a
    prefix of the reference: a time-subset of the log). Stamps must agree to 1 ms."""
    if len(trajectory) > len(reference):
        raise ValueError(f"trajectory has {len(trajectory)} scans, the reference {len(reference)}")
    errors = []
    for (t, x, y, _), (tr, xr, yr, _) in zip(trajectory, reference):
        if abs(t - tr) > 1e-3:
            raise ValueError(f"scan at {t:.6f} s has reference stamp {tr:.6f} s: not the same scans")
        errors.append(math.hypot(x - xr, y - yr))
    return errors


def lost_fraction(errors, threshold):
    """Share of the scans whose error is above the threshold."""
    return sum(1 for e in errors if e > threshold) / len(errors) if errors else float("nan")


def ends_lost(stamps, errors, threshold, tail_s=ENDS_LOST_S):
    """Whether every scan of the last tail_s seconds has an error above the threshold."""
    if not errors:
        return False
    end = stamps[-1]
    return all(e > threshold for t, e in zip(stamps, errors) if t >= end - tail_s)


def recovery_time(stamps, errors, kidnap_stamp, threshold, hold_s):
    """s from the kidnap to the first scan whose error is below the threshold and stays below it
    for hold_s seconds (or to the end of the run, if that comes first); None if never. 0 when the
    error never left the threshold."""
    candidate = None
    for t, e in zip(stamps, errors):
        if t < kidnap_stamp:
            continue
        if e > threshold:
            candidate = None
            continue
        if candidate is None:
            candidate = t
        if t - candidate >= hold_s:
            return candidate - kidnap_stamp
    return candidate - kidnap_stamp if candidate is not None else None


def summarize_runs(rows):
    """One summary of the runs (dicts of runs.csv) of a log, method and condition."""
    means = [r["mean_error_m"] for r in rows]
    recoveries = [r["recovery_s"] for r in rows if r["kidnapped"]]
    recovered = [x for x in recoveries if x is not None]
    return {
        "runs": len(rows),
        "mean_error_m": statistics.fmean(means),
        "mean_error_sd_m": statistics.stdev(means) if len(means) > 1 else 0.0,
        "median_error_m": statistics.median(r["median_error_m"] for r in rows),
        "lost_fraction": statistics.fmean(r["lost_fraction"] for r in rows),
        "failed_runs": sum(1 for r in rows if r["ends_lost"]),
        "kidnaps": len(recoveries),
        "recovered": len(recovered),
        "recovery_median_s": statistics.median(recovered) if recovered else None,
        "us_per_scan": statistics.fmean(r["us_per_scan"] for r in rows),
    }


# ---------------------------------------------------------------------------------------------
# Files.

def open_log(path):
    return gzip.open(path, "rt", encoding="utf-8", errors="replace") if path.endswith(".gz") else open(path, encoding="utf-8")


LASER_TYPES = ("FLASER", "RLASER", "ROBOTLASER1", "RAWLASER1")


def time_subset(log, out, duration):
    """Writes the lines of a CARMEN log up to the first laser line more than `duration` s after
    the first laser line (file order; Intel's stamps step back, so not a sort by time)."""
    first = None
    buffer = io.StringIO()
    with open_log(log) as f:
        for line in f:
            fields = line.split()
            if fields and fields[0] in LASER_TYPES and len(fields) >= 3:
                stamp = float(fields[-3])
                first = stamp if first is None else first
                if stamp - first > duration:
                    break
            buffer.write(line)
    if first is None:
        raise ValueError(f"{log}: no laser line")
    write_atomic(out, buffer.getvalue())


# ---------------------------------------------------------------------------------------------
# The benchmark.

def reference(args, log):
    """The graph-SLAM map and trajectory of the whole log, made once."""
    folder = os.path.join(args.out, "reference", log)
    if not os.path.exists(os.path.join(folder, "summary.json")):
        run([args.slam2d, "map", os.path.join(args.data, LOGS[log]), "--method", "graph", "--out", folder, "--quiet", "--json"], nice=True)
    return os.path.join(folder, "map.yaml"), read_trajectory(os.path.join(folder, "trajectory.txt"))


def run_group(args, log, condition, seed, methods, map_yaml, ref, plain_mcl):
    """The methods on one degraded log (log, condition, seed): a list of runs.csv rows."""
    _, _, faults, kidnap = CONDITIONS[condition]
    work = os.path.join(args.out, "runs", log, condition, f"seed{seed}")
    os.makedirs(work, exist_ok=True)
    source = os.path.join(args.data, LOGS[log])
    if args.duration:
        source = os.path.join(args.out, "subsets", f"{log}_{args.duration:g}s.clf")
    degraded = source
    if faults:
        degraded = os.path.join(work, "log.clf")
        command = [args.slam2d, "perturb", source, "--out", degraded, "--seed", str(seed), "--quiet", "--json"]
        for spec in faults:
            command += ["--fault", spec]
        run(command, nice=True)
    x, y, theta = ref[0][1:]
    rows = []
    try:
        for method in methods:
            result_path = os.path.join(work, f"{method}.json")
            if args.resume and os.path.exists(result_path):
                with open(result_path, encoding="utf-8") as f:
                    rows.append(json.load(f))
                continue
            trajectory_path = os.path.join(work, f"{method}.txt")
            command = [args.slam2d, "localize", degraded, "--map", map_yaml, "--initial", f"{x!r},{y!r},{theta!r}",
                       "--seed", str(seed), "--out", trajectory_path, "--json", "--quiet"]
            command += [plain_mcl if a == "@PLAIN_MCL" else a for a in METHODS[method]]
            kidnap_at = None
            if kidnap:
                duration = args.duration or (ref[-1][0] - ref[0][0])
                kidnap_at = KIDNAP_AT * duration + 10.0 * (seed - 1)
                command += ["--kidnap-at", f"{kidnap_at:g}", "--kidnap-by", KIDNAP_BY]
            summary = json.loads(run(command, nice=True))
            trajectory = read_trajectory(trajectory_path)
            os.remove(trajectory_path)
            errors = position_errors(trajectory, ref)
            stamps = [row[0] for row in trajectory]
            row = {
                "log": log, "method": method, "condition": condition, "seed": seed, "scans": len(errors),
                "mean_error_m": statistics.fmean(errors), "median_error_m": statistics.median(errors),
                "max_error_m": max(errors), "lost_fraction": lost_fraction(errors, args.threshold),
                "ends_lost": ends_lost(stamps, errors, args.threshold), "kidnapped": kidnap,
                "recovery_s": recovery_time(stamps, errors, stamps[0] + kidnap_at, args.threshold, args.hold) if kidnap else None,
                "reported_recovery_s": summary.get("recovered_after_s") if kidnap else None,
                "us_per_scan": 1e6 * summary["localizer_cpu_s"] / max(summary["scans"], 1),
                "cpu_s": summary["cpu_s"],
            }
            write_atomic(result_path, json.dumps(row))
            rows.append(row)
    finally:
        if degraded != source and os.path.exists(degraded):
            os.remove(degraded)
    return rows


def markdown(summaries, args):
    lines = [f"Threshold {args.threshold:g} m; hold {args.hold:g} s; "
             f"{'first %g s of each log' % args.duration if args.duration else 'whole logs'}.", "",
             "| log | method | condition | runs | mean error (m) | median error (m) | time lost | runs ending lost | "
             "kidnap: recovered, median recovery (s) | us per scan |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for s in summaries:
        recovery = f"{s['recovered']}/{s['kidnaps']}, {fmt(s['recovery_median_s'], 1)}" if s["kidnaps"] else ""
        lines.append(f"| {s['log']} | {s['method']} | {s['condition']} | {s['runs']} | {fmt(s['mean_error_m'])} ± "
                     f"{fmt(s['mean_error_sd_m'])} | {fmt(s['median_error_m'])} | {100 * s['lost_fraction']:.1f} % | "
                     f"{s['failed_runs']}/{s['runs']} | {recovery} | {s['us_per_scan']:.0f} |")
    return "\n".join(lines) + "\n"


def plot(summaries, path, logs, methods):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    levels = [n for n in NOISE_LEVELS]
    fig, axes = plt.subplots(2, len(logs), figsize=(3.0 * len(logs), 4.6), squeeze=False, sharex=True)
    for column, log in enumerate(logs):
        for method in methods:
            by_level = {CONDITIONS[s["condition"]][1]: s for s in summaries
                        if s["log"] == log and s["method"] == method and CONDITIONS[s["condition"]][0] == "odometry"}
            xs = [n for n in levels if n in by_level]
            if not xs:
                continue
            axes[0][column].plot(xs, [by_level[n]["mean_error_m"] for n in xs], marker="o", ms=3, label=method)
            axes[1][column].plot(xs, [100 * by_level[n]["lost_fraction"] for n in xs], marker="o", ms=3, label=method)
        axes[0][column].set_title(log, fontsize=9)
        axes[0][column].set_yscale("log")
        axes[1][column].set_xlabel("odometry noise (x base)", fontsize=8)
        for row in axes:
            row[column].tick_params(labelsize=7)
            row[column].grid(alpha=0.3)
    axes[0][0].set_ylabel("mean error (m)", fontsize=8)
    axes[1][0].set_ylabel("time lost (%)", fontsize=8)
    axes[0][-1].legend(fontsize=6)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=80)
    plt.close(fig)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-")
    with os.fdopen(fd, "wb") as f:
        f.write(buffer.getvalue())
    os.replace(tmp, path)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--slam2d", default="build/release/bin/slam2d")
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--logs", nargs="+", choices=list(LOGS), default=None)
    parser.add_argument("--methods", nargs="+", choices=list(METHODS), default=list(METHODS))
    parser.add_argument("--conditions", nargs="+", choices=list(CONDITIONS), default=list(CONDITIONS))
    parser.add_argument("--seeds", type=int, default=None, help="seeds 1..N (default 5; --quick 2)")
    parser.add_argument("--duration", type=float, default=None, help="s: only the first S s of each log (--quick: 300)")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--jobs", type=int, default=1, choices=[1, 2])
    parser.add_argument("--threshold", type=float, default=1.0, help="m: an error above this is lost")
    parser.add_argument("--hold", type=float, default=10.0, help="s the error must stay below the threshold to count as recovered")
    parser.add_argument("--out", default="/tmp/slam2d_localize_benchmark")
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    args.logs = args.logs or list(LOGS)
    args.seeds = args.seeds or (2 if args.quick else 5)
    if args.duration is None and args.quick:
        args.duration = 300.0
    if args.seeds < 1 or (args.duration is not None and args.duration <= 0):
        parser.error("--seeds must be >= 1 and --duration > 0")
    if not os.access(args.slam2d, os.X_OK):
        parser.error(f"--slam2d {args.slam2d}: not an executable (build the slam2d target)")
    for log in args.logs:
        if not os.path.exists(os.path.join(args.data, LOGS[log])):
            parser.error(f"{os.path.join(args.data, LOGS[log])}: no such log (set --data or SLAM2D_DATA)")
    os.makedirs(args.out, exist_ok=True)
    plain_mcl = os.path.join(args.out, "mcl_without_random_samples.yaml")
    write_atomic(plain_mcl, "method: mcl\naugmented: false\n")
    started = time.monotonic()

    references = {}
    for log in args.logs:
        if not args.quiet:
            print(f"\rreference: graph SLAM on {log} ...", end="", file=sys.stderr, flush=True)
        references[log] = reference(args, log)
        if args.duration:
            subset = os.path.join(args.out, "subsets", f"{log}_{args.duration:g}s.clf")
            if not os.path.exists(subset):
                time_subset(os.path.join(args.data, LOGS[log]), subset, args.duration)

    groups = []
    for log in args.logs:
        for condition in args.conditions:
            randomized = bool(CONDITIONS[condition][2]) or CONDITIONS[condition][3]
            for seed in range(1, args.seeds + 1):
                methods = [m for m in args.methods if randomized or m in RANDOM_METHODS or seed == 1]
                groups.append((log, condition, seed, methods))
    total = sum(len(g[3]) for g in groups)
    done = [0]
    lock = threading.Lock()

    def task(group):  # one degraded log at a time: perturbed logs are removed after their methods ran
        log, condition, seed, methods = group
        rows = run_group(args, log, condition, seed, methods, *references[log], plain_mcl)
        with lock:
            done[0] += len(methods)
            if not args.quiet:
                elapsed = time.monotonic() - started
                print(f"\r[{done[0]}/{total}] {log} {condition} seed {seed}, {elapsed:.0f} s   ", end="",
                      file=sys.stderr, flush=True)
        return rows

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(task, groups))
    if not args.quiet:
        print(file=sys.stderr)
    rows = [row for group_rows in results for row in group_rows]

    summaries = []
    for log in args.logs:
        for method in args.methods:
            for condition in args.conditions:
                selected = [r for r in rows if r["log"] == log and r["method"] == method and r["condition"] == condition]
                if selected:
                    summaries.append({"log": log, "method": method, "condition": condition, **summarize_runs(selected)})

    fields = list(rows[0].keys())
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_atomic(os.path.join(args.out, "runs.csv"), buffer.getvalue())
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(summaries[0].keys()), lineterminator="\n")
    writer.writeheader()
    writer.writerows(summaries)
    write_atomic(os.path.join(args.out, "summary.csv"), buffer.getvalue())
    write_atomic(os.path.join(args.out, "summary.md"), markdown(summaries, args))
    document = {"settings": {"logs": args.logs, "methods": args.methods, "conditions": {c: CONDITIONS[c][2] for c in args.conditions},
                             "seeds": args.seeds, "duration_s": args.duration, "threshold_m": args.threshold,
                             "hold_s": args.hold, "kidnap_by": KIDNAP_BY, "base_noise": BASE_NOISE},
                "wall_s": time.monotonic() - started, "summaries": summaries}
    write_atomic(os.path.join(args.out, "summary.json"), json.dumps(document, indent=1) + "\n")
    if any(CONDITIONS[c][0] == "odometry" for c in args.conditions):
        plot(summaries, os.path.join(args.out, "localize_noise.png"), args.logs, args.methods)
    if args.json:
        print(json.dumps(document, indent=1))
    else:
        print(markdown(summaries, args), end="")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (RuntimeError, ValueError, OSError) as error:
        print(f"localize_benchmark: {error}", file=sys.stderr)
        sys.exit(1)
