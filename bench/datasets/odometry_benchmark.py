#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Scan-to-scan odometry benchmark on the raw logs of Kuemmerle et al. 2009 (intel, aces, fr079).

For each matcher and log this runs
    slam2d odometry LOG --matcher NAME --out TRAJ --quiet --json
    slam2d eval TRAJ --relations RELATIONS --json
and prints one table (or, with --json, one JSON document): the relation error (mean translational
error in m, mean rotational error in deg), the CPU time per match (log parsing included, as in
CSM's sm2 figure), the mean iterations and the scans whose match failed the gate.

Usage: bench/datasets/odometry_benchmark.py [--slam2d build/release/bin/slam2d] [--data /work/shared/data]
                                            [--matchers pl-icp ...] [--logs intel aces fr079]
                                            [--out /tmp/slam2d_odometry_benchmark] [--json]
"""

import argparse
import json
import os
import sys

from common import run_json

LOGS = {
    "intel": ("intel/intel.clf.gz", "intel/intel.relations"),
    "aces": ("aces/aces.clf.gz", "aces/aces.relations"),
    "fr079": ("fr079/fr079.clf.gz", "fr079/fr079.relations"),
}
# Kuemmerle et al. 2009, Table 1, 'scan matching' column: mean translational error (m).
SCAN_MATCHING_2009 = {"intel": 0.220, "aces": 0.173, "fr079": 0.258}


def run_one(args, matcher, log):
    log_file, relations = LOGS[log]
    trajectory = os.path.join(args.out, f"{matcher}_{log}.txt")
    odometry_command = [args.slam2d, "odometry", os.path.join(args.data, log_file), "--matcher", matcher,
                        "--out", trajectory, "--quiet", "--json"]
    summary = run_json(odometry_command)
    eval_command = [args.slam2d, "eval", trajectory, "--relations", os.path.join(args.data, relations), "--json"]
    error = run_json(eval_command)
    return {
        "matcher": matcher, "log": log,
        "trans_mean_m": error["trans_mean"], "rot_mean_deg": error["rot_mean_deg"],
        "us_per_match": summary["us_per_match"], "mean_iterations": summary["mean_iterations"],
        "failures": summary["failures"], "scans": summary["scans"], "cpu_s": summary["cpu_s"],
        "scan_matching_2009_m": SCAN_MATCHING_2009[log],
        "odometry_command": " ".join(odometry_command), "eval_command": " ".join(eval_command),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--matchers", nargs="+", default=["pl-icp"])
    parser.add_argument("--logs", nargs="+", default=list(LOGS), choices=list(LOGS))
    parser.add_argument("--out", default="/tmp/slam2d_odometry_benchmark")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    rows = [run_one(args, matcher, log) for matcher in args.matchers for log in args.logs]
    if args.json:
        json.dump({"results": rows}, sys.stdout, indent=2)
        print()
        return
    print("| matcher | log | trans. mean (m) | rot. mean (deg) | µs/match | iterations | failures |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['matcher']} | {r['log']} | {r['trans_mean_m']:.3f} | {r['rot_mean_deg']:.2f} | {r['us_per_match']:.0f}"
              f" | {r['mean_iterations']:.1f} | {r['failures']}/{r['scans']} |")


if __name__ == "__main__":
    main()
