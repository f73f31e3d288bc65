#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Scan-matcher comparison on the three real logs (the protocol of Pomerleau et al. 2013).

For each log this runs
    slam2d match-bench LOG --reference REF --matchers a,b,... --levels M:DEG,...
                       --pairs N --distance D --seed S --quiet --json --out OUT/NAME-REFERENCE
with, by --reference, either the SLAM-corrected logs and their own scan poses (`corrected`, the
default; a raw log is refused as "corrected"), or the raw logs and a graph SLAM trajectory of
each, made first by `slam2d map LOG --method graph --out OUT/NAME-graph-slam` (`graph`). It
prints one Markdown table per log (per matcher and level: success rate, the translation and
rotation error at the 50th and 95th percentiles, CPU time per match) and, with --figures DIR,
draws each log's error CDFs with match_bench_cdf.py to DIR/match_bench_NAME[_graph].png.

Usage: bench/datasets/match_bench_table.py [--slam2d build/release/bin/slam2d] [--data /work/shared/data]
                                           [--reference corrected|graph] [--logs LOG ...] [--matchers ...]
                                           [--levels 0.05:2,0.1:5,0.2:10,0.5:20] [--pairs 200]
                                           [--distance 1] [--seed 1] [--out /tmp/match_bench]
                                           [--figures docs/images] [--json]
"""

import argparse
import json
import os
import subprocess
import sys

MATCHERS = ["icp", "trimmed-icp", "pl-icp", "point-to-plane", "idc", "correlative", "ga-icp"]
LOGS = {"corrected": ["intel/intel-corrected.log.gz", "aces/aces-corrected.log.gz", "fr079/freiburg-079-corrected.log.gz"],
        "graph": ["intel/intel.clf.gz", "aces/aces.clf.gz", "fr079/fr079.clf.gz"]}
TITLES = {"corrected": "the corrected log's poses", "graph": "a graph SLAM trajectory of the raw log"}
HERE = os.path.dirname(os.path.abspath(__file__))


def log_name(log):
    """intel/intel-corrected.log.gz -> intel: the data folder's name, else the file's stem."""
    folder = os.path.basename(os.path.dirname(log))
    return folder or os.path.basename(log).split("-corrected")[0].split(".")[0]


def graph_trajectory(args, log):
    out = os.path.join(args.out, log_name(log) + "-graph-slam")
    command = [args.slam2d, "map", os.path.join(args.data, log), "--method", "graph", "--out", out, "--quiet"]
    subprocess.run(command, check=True, capture_output=True, text=True)
    return os.path.join(out, "trajectory.txt"), " ".join(command).replace(args.data, "$SLAM2D_DATA")


def run_log(args, log):
    out = os.path.join(args.out, f"{log_name(log)}-{args.reference}")
    reference, prepared = "corrected", None
    if args.reference == "graph":
        reference, prepared = graph_trajectory(args, log)
    command = [args.slam2d, "match-bench", os.path.join(args.data, log), "--reference", reference,
               "--matchers", ",".join(args.matchers), "--levels", args.levels, "--pairs", str(args.pairs),
               "--distance", str(args.distance), "--seed", str(args.seed), "--quiet", "--json", "--out", out]
    result = subprocess.run(command, check=True, capture_output=True, text=True)
    summary = json.loads(result.stdout)
    summary["command"] = " ".join(command).replace(args.data, "$SLAM2D_DATA")
    summary["prepared_by"] = prepared
    summary["out"] = out
    return summary


def draw_figure(args, summary, log):
    suffix = "" if args.reference == "corrected" else "_" + args.reference
    figure = os.path.join(args.figures, f"match_bench_{log_name(log)}{suffix}.png")
    command = [sys.executable, os.path.join(HERE, "match_bench_cdf.py"), os.path.join(summary["out"], "cases.csv"),
               "--out", figure, "--title",
               f"{log_name(log)}: {summary['pairs']} pairs {summary['distance']:g} m apart, "
               f"reference: {TITLES[args.reference]}",
               "--success-trans", str(summary["success_trans"]), "--success-rot", str(summary["success_rot_deg"])]
    subprocess.run(command, check=True)
    return figure


def print_table(summary):
    if summary["prepared_by"]:
        print(f"`{summary['prepared_by']}`, then")
    print(f"`{summary['command']}`\n")
    print(f"Reference: {summary['reference']['description']}. {summary['scans']} scans, {summary['pairs']} pairs; "
          f"success = error under {summary['success_trans']} m and {summary['success_rot_deg']} deg.\n")
    levels = summary["levels"]
    header = "| matcher | " + " | ".join(f"σ {v['sigma_trans']:g} m, {v['sigma_rot_deg']:g}°" for v in levels.values())
    print(header + " | µs/match |")
    print("|---" * (len(levels) + 2) + "|")
    for matcher in summary["matchers"]:
        cells = []
        for v in levels.values():
            r = v["matchers"][matcher]
            cells.append(f"{100 * r['success_rate']:.0f}% · {r['trans_error_p50']:.3f}/{r['trans_error_p95']:.2f} m · "
                         f"{r['rot_error_deg_p50']:.2f}/{r['rot_error_deg_p95']:.1f}°")
        times = [v["matchers"][matcher]["us_per_match"] for v in levels.values()]
        print(f"| {matcher} | " + " | ".join(cells) + f" | {sum(times) / len(times):.0f} |")
    print()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--reference", choices=sorted(LOGS), default="corrected")
    parser.add_argument("--logs", nargs="+", help="logs under --data (default: by --reference)")
    parser.add_argument("--matchers", nargs="+", default=MATCHERS)
    parser.add_argument("--levels", default="0.05:2,0.1:5,0.2:10,0.5:20")
    parser.add_argument("--pairs", type=int, default=200)
    parser.add_argument("--distance", type=float, default=1.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", default="/tmp/match_bench", help="folder for each log's cases.csv and summary.json")
    parser.add_argument("--figures", default="", help="folder for the CDF figures (none if empty)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    args = parser.parse_args()
    args.logs = args.logs or LOGS[args.reference]

    summaries = []
    for log in args.logs:
        summary = run_log(args, log)
        if args.figures:
            summary["figure"] = draw_figure(args, summary, log)
        summaries.append(summary)
    if args.json:
        json.dump({"results": summaries}, sys.stdout, indent=2)
        print()
        return
    for summary in summaries:
        print_table(summary)


if __name__ == "__main__":
    main()
