#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Match two scans of a log with a scan matcher and plot them before and after.

    PYTHONPATH=build/release/python examples/python/match_two_scans.py LOG [--method pl-icp] [--gap 5] [--out match.png]
"""
import argparse

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import slam2d  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("log")
parser.add_argument("--method", default="pl-icp", choices=slam2d.matcher_names())
parser.add_argument("--first", type=int, default=100, help="index of the target scan")
parser.add_argument("--gap", type=int, default=5, help="scans between target and source")
parser.add_argument("--out", default="match.png")
args = parser.parse_args()

scans = [m for m in slam2d.read_log(args.log) if m["kind"] == "scan"]
target, source = scans[args.first], scans[args.first + args.gap]
guess = target["odom"].inverse() * source["odom"]  # the odometry's motion between them
result = slam2d.match(target["scan"].points(), source["scan"].points(), guess, method=args.method)
print(f"{args.method}: {result.pose} (odometry said {guess}), {result.iterations} iterations, "
      f"{result.inliers} inliers, degenerate: {result.degenerate}")
print("covariance (m^2, m rad, rad^2):\n", np.array2string(result.covariance, precision=6))

def placed(pose, points):
    return np.array([pose * p for p in points])

fig, axes = plt.subplots(1, 2, figsize=(12, 6))
for ax, pose, title in ((axes[0], guess, "odometry guess"), (axes[1], result.pose, args.method)):
    ax.plot(*target["scan"].points().T, ".", ms=2, label="target")
    ax.plot(*placed(pose, source["scan"].points()).T, ".", ms=2, label="source")
    ax.set_title(title)
    ax.set_aspect("equal")
    ax.legend()
fig.savefig(args.out, dpi=120)
print("wrote", args.out)
