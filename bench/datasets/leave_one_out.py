#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Leave-one-out check of one setting over the public logs (docs/defaults.md).

For every value of a grid and every log (intel, aces, fr079) runs one slam2d command, then
    slam2d eval TRAJ --relations $SLAM2D_DATA/LOG/LOG.relations --json
and prints two markdown tables: the mean translational relation error per value and log, and,
for each choice of held-out log, the value with the lowest geometric mean of the other logs'
errors (scale-free: no log weighs more for having larger errors), its error on the held-out log,
the default's, and the held-out log's best over the grid.

The command is a template after `--`: {log} is the log's path, {out} a fresh output path, {value}
the value. A command whose template contains `map` writes a folder (the trajectory is
{out}/trajectory.txt); any other writes the trajectory to {out}.

    bench/datasets/leave_one_out.py --values 0 0.05 0.1 0.2 --default 0.1 -- \\
        odometry {log} --matcher pl-icp --keyframe {value} --out {out} --json --quiet
    bench/datasets/leave_one_out.py --values 1 2 3 4 --default 3 -- \\
        map {log} --method hector --levels {value} --out {out} --json --quiet
"""
import argparse
import json
import math
import os

from common import run_json

LOGS = ["intel", "aces", "fr079"]


def relation_error(args, template, value, log):
    out = os.path.join(args.out, f"{log}_{value}")
    log_path = os.path.join(args.data, log, f"{log}.clf.gz")
    command = [args.slam2d] + [word.format(log=log_path, out=out, value=value) for word in template]
    run_json(command)
    trajectory = os.path.join(out, "trajectory.txt") if "map" in template else out
    relations = os.path.join(args.data, log, f"{log}.relations")
    return run_json([args.slam2d, "eval", trajectory, "--relations", relations, "--json"])["trans_mean"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--values", nargs="+", required=True)
    parser.add_argument("--default", required=True, help="the current default (one of --values)")
    parser.add_argument("--out", default="/tmp/slam2d_leave_one_out")
    parser.add_argument("--json", action="store_true", help="print the errors as JSON instead of tables")
    parser.add_argument("template", nargs=argparse.REMAINDER, help="-- then the slam2d command")
    args = parser.parse_args()
    template = args.template[1:] if args.template[:1] == ["--"] else args.template
    if not template or args.default not in args.values:
        parser.error("give a command after -- and a --default that is one of --values")
    os.makedirs(args.out, exist_ok=True)

    error = {(v, log): relation_error(args, template, v, log) for v in args.values for log in LOGS}
    if args.json:
        print(json.dumps({f"{v}/{log}": e for (v, log), e in error.items()}, indent=1))
        return
    print("| value | " + " | ".join(LOGS) + " |")
    print("|---|" + "---:|" * len(LOGS))
    for v in args.values:
        mark = " (default)" if v == args.default else ""
        print(f"| {v}{mark} | " + " | ".join(f"{error[(v, log)]:.4f}" for log in LOGS) + " |")
    print()
    print("| held out | picked on | value picked | held-out error at it (m) | at the default (m) | held-out best (m) | picked / best |")
    print("|---|---|---|---:|---:|---:|---:|")
    for held_out in LOGS:
        others = [log for log in LOGS if log != held_out]
        picked = min(args.values, key=lambda v: math.prod(error[(v, log)] for log in others))
        best = min(args.values, key=lambda v: error[(v, held_out)])
        print(f"| {held_out} | {', '.join(others)} | {picked} | {error[(picked, held_out)]:.4f} | "
              f"{error[(args.default, held_out)]:.4f} | {error[(best, held_out)]:.4f} ({best}) | "
              f"{error[(picked, held_out)] / error[(best, held_out)]:.2f} |")


if __name__ == "__main__":
    main()
