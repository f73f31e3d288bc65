#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Scan-matcher benchmark on SLAM-corrected logs (the protocol of Pomerleau et al. 2013).

For each log this runs
    slam2d match-bench LOG --matchers a,b,... --pairs N --distance D
                       --perturb-trans M --perturb-rot DEG --seed S --quiet --json
(the reference is the log's own laser poses, which the corrected logs carry) and prints one
Markdown table per log: success rate (error under 0.1 m and 2 deg), translation and rotation
error percentiles 50/75/95, CPU time per match and mean iterations.

Usage: bench/datasets/match_bench_table.py [--slam2d build/release/bin/slam2d] [--data /work/shared/data]
                                           [--logs intel/intel-corrected.log.gz ...] [--matchers ...]
                                           [--pairs 200] [--distance 1] [--perturb-trans 0.1]
                                           [--perturb-rot 5] [--seed 1] [--json]
"""

import argparse
import json
import os
import subprocess
import sys

MATCHERS = ["icp", "icp-accelerated", "trimmed-icp", "pl-icp", "point-to-plane", "imrp", "idc",
            "tangent-search", "boolean-icp", "soft-icp", "ga-icp", "correlative", "pipeline"]
LOGS = ["intel/intel-corrected.log.gz", "fr079/freiburg-079-corrected.log.gz"]


def run_log(args, log):
    command = [args.slam2d, "match-bench", os.path.join(args.data, log), "--matchers", ",".join(args.matchers),
               "--pairs", str(args.pairs), "--distance", str(args.distance),
               "--perturb-trans", str(args.perturb_trans), "--perturb-rot", str(args.perturb_rot),
               "--seed", str(args.seed), "--quiet", "--json"]
    result = subprocess.run(command, check=True, capture_output=True, text=True)
    summary = json.loads(result.stdout)
    summary["command"] = " ".join(command)
    return summary


def print_table(summary):
    print(f"`{summary['command']}` ({summary['scans']} scans, {summary['pairs']} pairs)\n")
    print("| matcher | success | trans. p50 / p75 / p95 (m) | rot. p50 / p75 / p95 (deg) | µs/match | iterations |")
    print("|---|---|---|---|---|---|")
    for name, r in summary["matchers"].items():
        print(f"| {name} | {100 * r['success_rate']:.1f}% "
              f"| {r['trans_error_p50']:.3f} / {r['trans_error_p75']:.3f} / {r['trans_error_p95']:.3f} "
              f"| {r['rot_error_deg_p50']:.2f} / {r['rot_error_deg_p75']:.2f} / {r['rot_error_deg_p95']:.2f} "
              f"| {r['us_per_match']:.0f} | {r['mean_iterations']:.1f} |")
    print()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--logs", nargs="+", default=LOGS)
    parser.add_argument("--matchers", nargs="+", default=MATCHERS)
    parser.add_argument("--pairs", type=int, default=200)
    parser.add_argument("--distance", type=float, default=1.0)
    parser.add_argument("--perturb-trans", type=float, default=0.1)
    parser.add_argument("--perturb-rot", type=float, default=5.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    args = parser.parse_args()

    summaries = [run_log(args, log) for log in args.logs]
    if args.json:
        json.dump({"results": summaries}, sys.stdout, indent=2)
        print()
        return
    for summary in summaries:
        print_table(summary)


if __name__ == "__main__":
    main()
