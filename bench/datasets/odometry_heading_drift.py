#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Where scan odometry's heading drift comes from: its keyframe chain, step by step, against a
reference trajectory and against the wheel odometry (docs/methods/pl_icp.md, "Why Intel stays
near CSM").

Scan odometry places each keyframe by one match from the keyframe before, so its heading error is
the sum of the heading errors of those chain steps. Per log this runs
    slam2d odometry LOG --matcher NAME --out TRAJ --covariance-csv CSV   (the `target` column: the chain)
    slam2d map LOG --method graph --out DIR                              (the reference, unless --reference)
    slam2d map LOG --method odometry --out DIR                           (the wheel odometry per scan)
and prints, per time window, the chain's heading drift (the sum of its steps' errors against the
reference), how much of it came from steps more than --large degrees off (a few bad matches) and
the mean heading error of the wheel odometry over the same steps; then the regression slope of the
steps' errors on the odometry's (how much of the guess's error the matches keep).

Usage: bench/datasets/odometry_heading_drift.py [--slam2d build/release/bin/slam2d] [--data /work/shared/data]
                                                [--logs intel aces fr079] [--matcher pl-icp] [--window 120]
                                                [--large 0.5] [--out /tmp/slam2d_heading_drift] [--json]
"""

import argparse
import csv
import json
import math
import os
import sys

from common import read_trajectory, run, run_json

LOGS = {"intel": "intel/intel.clf.gz", "aces": "aces/aces.clf.gz", "fr079": "fr079/fr079.clf.gz"}


def wrap(angle):
    return math.atan2(math.sin(angle), math.cos(angle))


def heading_step(trajectory, a, b):
    return wrap(trajectory[b][3] - trajectory[a][3])


def chain(covariance_csv):
    """(target, keyframe) per chain step: each keyframe with the keyframe it was matched against."""
    with open(covariance_csv, encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    target_of = {int(r["index"]): int(r["target"]) for r in rows if r["target"]}
    keyframes = sorted(set(target_of.values()))
    return [(target_of[k], k) for k in keyframes if k in target_of]


def analyse(steps, odometry, trajectory, reference, window, large):
    t0 = trajectory[0][0]
    errors, odometry_errors, windows = [], [], {}
    for a, b in steps:
        reference_step = heading_step(reference, a, b)
        e = wrap(heading_step(trajectory, a, b) - reference_step)
        o = wrap(heading_step(odometry, a, b) - reference_step)
        errors.append(e)
        odometry_errors.append(o)
        w = windows.setdefault(int((trajectory[b][0] - t0) // window), {"steps": 0, "drift": 0.0, "large": 0.0,
                                                                          "large_steps": 0, "odometry": 0.0})
        w["steps"] += 1
        w["drift"] += e
        w["odometry"] += o
        if abs(e) > math.radians(large):
            w["large"] += e
            w["large_steps"] += 1
    rows = [{"from_s": k * window, "to_s": (k + 1) * window, "steps": w["steps"],
             "drift_deg": math.degrees(w["drift"]), "from_large_steps_deg": math.degrees(w["large"]),
             "large_steps": w["large_steps"], "odometry_error_per_step_deg": math.degrees(w["odometry"] / w["steps"])}
            for k, w in sorted(windows.items())]
    cumulative, worst = 0.0, 0.0
    for e in errors:
        cumulative += e
        worst = max(worst, abs(cumulative))
    slope = sum(e * o for e, o in zip(errors, odometry_errors)) / max(sum(o * o for o in odometry_errors), 1e-30)
    return {"steps": len(steps), "drift_deg": math.degrees(sum(errors)), "max_abs_cumulative_deg": math.degrees(worst),
            "from_large_steps_deg": math.degrees(sum(e for e in errors if abs(e) > math.radians(large))),
            "large_steps": sum(1 for e in errors if abs(e) > math.radians(large)),
            "mean_abs_step_error_deg": math.degrees(sum(abs(e) for e in errors) / max(len(errors), 1)),
            "odometry_error_per_step_deg": math.degrees(sum(odometry_errors) / max(len(errors), 1)),
            "slope_on_odometry_error": slope, "windows": rows}


def run_log(args, log):
    path = os.path.join(args.data, LOGS[log])
    out = os.path.join(args.out, log)
    os.makedirs(out, exist_ok=True)
    trajectory_path, covariance_csv = os.path.join(out, "odometry.txt"), os.path.join(out, "chain.csv")
    run_json([args.slam2d, "odometry", path, "--matcher", args.matcher, "--out", trajectory_path,
              "--covariance-csv", covariance_csv, "--quiet", "--json"])
    reference_path = args.reference
    if not reference_path:
        run([args.slam2d, "map", path, "--method", "graph", "--out", os.path.join(out, "graph"), "--quiet"])
        reference_path = os.path.join(out, "graph", "trajectory.txt")
    run([args.slam2d, "map", path, "--method", "odometry", "--out", os.path.join(out, "wheel"), "--quiet"])
    trajectory, reference = read_trajectory(trajectory_path), read_trajectory(reference_path)
    odometry = read_trajectory(os.path.join(out, "wheel", "trajectory.txt"))
    if not len(trajectory) == len(reference) == len(odometry):
        raise SystemExit(f"{log}: {len(trajectory)} odometry poses, {len(reference)} reference, {len(odometry)} wheel: "
                         "the reference must have one pose per scan")
    result = analyse(chain(covariance_csv), odometry, trajectory, reference, args.window, args.large)
    result["log"] = log
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--logs", nargs="+", default=list(LOGS), choices=list(LOGS))
    parser.add_argument("--matcher", default="pl-icp")
    parser.add_argument("--reference", help="a trajectory with one pose per scan (default: graph SLAM's)")
    parser.add_argument("--window", type=float, default=120.0, help="s per row")
    parser.add_argument("--large", type=float, default=0.5, help="deg: a chain step this far off is a bad match")
    parser.add_argument("--out", default="/tmp/slam2d_heading_drift")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    results = [run_log(args, log) for log in args.logs]
    if args.json:
        json.dump({"results": results}, sys.stdout, indent=2)
        print()
        return
    for r in results:
        print(f"{r['log']}: {r['steps']} chain steps, heading drift {r['drift_deg']:.1f} deg (largest |cumulative| "
              f"{r['max_abs_cumulative_deg']:.1f}), {r['large_steps']} steps over {args.large} deg give "
              f"{r['from_large_steps_deg']:.1f} deg; mean |step error| {r['mean_abs_step_error_deg']:.3f} deg; wheel "
              f"odometry {r['odometry_error_per_step_deg']:+.3f} deg per step; slope on it {r['slope_on_odometry_error']:+.3f}")
        print("| from (s) | steps | drift (deg) | from large steps (deg) | large steps | odometry error / step (deg) |")
        print("|---:|---:|---:|---:|---:|---:|")
        for w in r["windows"]:
            print(f"| {w['from_s']:.0f} | {w['steps']} | {w['drift_deg']:+.2f} | {w['from_large_steps_deg']:+.2f} | "
                  f"{w['large_steps']} | {w['odometry_error_per_step_deg']:+.3f} |")


if __name__ == "__main__":
    main()
