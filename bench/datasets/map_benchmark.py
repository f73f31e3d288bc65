#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Mapping benchmark on the raw logs of Kuemmerle et al. 2009 (intel, aces, fr079).

For each log (and each mode: with and without odometry) this runs
    slam2d map LOG --method METHOD [--no-odometry] --out DIR --quiet --json
    slam2d eval DIR/trajectory.txt --relations RELATIONS --json
and prints one table (or, with --json, one JSON document) with the relation error (mean/std of
the translational error in m, mean rotational error in deg), the CPU seconds of the mapping run
and its real-time factor (log duration / CPU time). Each log's runs also go into one HTML report
(slam2d report, docs/report.md): OUT/report_LOG/index.html.

Usage: bench/datasets/map_benchmark.py [--slam2d build/release/bin/slam2d] [--data /work/shared/data]
                                       [--method hector] [--logs intel aces fr079] [--modes odometry no-odometry]
                                       [--out /tmp/slam2d_map_benchmark] [--json]
"""

import argparse
import json
import os
import sys

from common import run_json, write_report

LOGS = {
    "intel": ("intel/intel.clf.gz", "intel/intel.relations"),
    "aces": ("aces/aces.clf.gz", "aces/aces.relations"),
    "fr079": ("fr079/fr079.clf.gz", "fr079/fr079.relations"),
}
# Kuemmerle et al. 2009, Table 1, 'scan matching' column: mean translational error (m).
SCAN_MATCHING_2009 = {"intel": 0.220, "aces": 0.173, "fr079": 0.258}


def run_one(args, log, mode):
    log_file, relations = LOGS[log]
    out_dir = os.path.join(args.out, f"{args.method}_{log}_{mode}")
    map_command = [args.slam2d, "map", os.path.join(args.data, log_file), "--method", args.method,
                   "--out", out_dir, "--quiet", "--json"]
    if mode == "no-odometry":
        map_command.append("--no-odometry")
    summary = run_json(map_command)
    eval_command = [args.slam2d, "eval", os.path.join(out_dir, "trajectory.txt"), "--relations",
                    os.path.join(args.data, relations), "--json"]
    error = run_json(eval_command)
    return {
        "log": log, "mode": mode, "method": args.method,
        "trans_mean_m": error["trans_mean"], "trans_std_m": error["trans_std"],
        "rot_mean_deg": error["rot_mean_deg"], "relations": error["relations"],
        "cpu_s": summary["cpu_s"], "realtime_factor": summary["realtime_factor"],
        "scans": summary["scans"], "scan_matching_2009_m": SCAN_MATCHING_2009[log],
        "map_command": " ".join(map_command), "eval_command": " ".join(eval_command), "out": out_dir,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--method", default="hector")
    parser.add_argument("--logs", nargs="+", default=list(LOGS), choices=list(LOGS))
    parser.add_argument("--modes", nargs="+", default=["odometry", "no-odometry"], choices=["odometry", "no-odometry"])
    parser.add_argument("--out", default="/tmp/slam2d_map_benchmark")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()

    rows = [run_one(args, log, mode) for log in args.logs for mode in args.modes]
    for log in args.logs:
        page = write_report(args.slam2d, [r["out"] for r in rows if r["log"] == log], os.path.join(args.out, f"report_{log}"),
                            os.path.join(args.data, LOGS[log][1]), os.path.join(args.data, LOGS[log][0]))
        print(f"report: {page}", file=sys.stderr)
    if args.json:
        json.dump({"method": args.method, "results": rows}, sys.stdout, indent=2)
        print()
        return
    print(f"{'log':6} {'mode':12} {'trans mean':>10} {'trans std':>10} {'rot mean':>9} {'cpu s':>7} {'x realtime':>10} {'2009 SM':>8}")
    for r in rows:
        print(f"{r['log']:6} {r['mode']:12} {r['trans_mean_m']:10.3f} {r['trans_std_m']:10.3f} {r['rot_mean_deg']:9.3f}"
              f" {r['cpu_s']:7.2f} {r['realtime_factor']:10.0f} {r['scan_matching_2009_m']:8.3f}")


if __name__ == "__main__":
    main()
