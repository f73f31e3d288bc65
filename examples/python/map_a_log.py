#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Map a log (CARMEN or bag) with a SLAM method and show the map with the trajectory.

    PYTHONPATH=build/release/python examples/python/map_a_log.py LOG [--method graph] [--relations FILE] [--out map.png]
"""
import argparse

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import slam2d  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("log")
parser.add_argument("--method", default="graph", choices=["odometry", "hector", "graph", "rbpf"])
parser.add_argument("--relations", help="a relations file: print the relation error")
parser.add_argument("--out", default="map.png")
args = parser.parse_args()

run = slam2d.map_log(args.log, method=args.method)
print(f"{args.method}: {len(run.trajectory)} scans, {run.summary['cpu_s']:.2f} s CPU")
if args.relations:
    error = slam2d.relation_error(run.trajectory, args.relations)
    print(f"relation error: {error['trans_mean']:.4f} m, {error['rot_mean_deg']:.3f} deg over {error['relations']} relations")

cells = run.map["cells"].astype(float)
image = np.where(cells < 0, 0.5, 1.0 - cells / 100.0)  # unknown grey, occupied black, free white
origin, resolution = run.map["origin"], run.map["resolution"]
extent = [origin.x, origin.x + cells.shape[1] * resolution, origin.y, origin.y + cells.shape[0] * resolution]
plt.figure(figsize=(10, 10))
plt.imshow(image, cmap="gray", origin="lower", extent=extent, vmin=0, vmax=1)
plt.plot(run.trajectory[:, 1], run.trajectory[:, 2], "r-", lw=0.8)
plt.title(f"{args.log}: {args.method}")
plt.savefig(args.out, dpi=150)
print("wrote", args.out)
