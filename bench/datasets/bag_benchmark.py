#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The public logs as bags against their CARMEN files (issue 22's figures).

For each log (intel, aces, fr079) and each source (the CARMEN log; the ROS 1 bag; the ROS 2 MCAP
and sqlite3 bags where ../shared/data/bags has them) this runs
    slam2d map SOURCE --method graph --trajectory-frame sensor [OPTIONS] --out DIR --quiet --json
    slam2d map SOURCE --method rbpf --seed S ...                 (seeds 1..N: RBPF's spread is wide)
    slam2d eval DIR/trajectory.txt --relations RELATIONS --json
and prints the scan count, the mean translational relation error of graph SLAM and the median and
spread of RBPF's over the seeds, whether the bag formats of one log give byte-identical
trajectories, and the time `slam2d info` takes to read each source (best of 3).

OPTIONS: the Intel bags declare 180 deg for the 180 beams of a 1 deg scanner, so they are read
with --fov 180 (docs/bags.md); --scan-odometry latest is run as a second variant for the bags.

Usage: bench/datasets/bag_benchmark.py [--slam2d build/release/bin/slam2d] [--data /work/shared/data]
                                       [--seeds 5] [--logs intel aces fr079] [--out /tmp/slam2d_bag_benchmark] [--json]
"""

import argparse
import gzip
import json
import os
import shutil
import statistics
import subprocess
import time

from common import run_json

LOGS = ["intel", "aces", "fr079"]


def unpack_rosbag2(folder, into):
    """A copy of a rosbag2 folder whose storage files are stored as NAME.gz, gunzipped."""
    target = os.path.join(into, os.path.basename(folder))
    if os.path.isdir(target):
        return target
    os.makedirs(target)
    for name in os.listdir(folder):
        source = os.path.join(folder, name)
        if name.endswith(".gz"):
            with gzip.open(source, "rb") as zipped, open(os.path.join(target, name[:-3]), "wb") as plain:
                shutil.copyfileobj(zipped, plain)
        else:
            shutil.copy(source, target)
    return target


def sources(data, log, unpacked):
    found = {"carmen": os.path.join(data, log, f"{log}.clf.gz"), "ros1": os.path.join(data, "bags", "ros1", f"{log}.orig.bag")}
    for kind in ("mcap", "db3"):
        folder = os.path.join(data, "bags", "ros2", f"{log}_{kind}")
        if os.path.isdir(folder):
            found[kind] = unpack_rosbag2(folder, unpacked)
    return found


def relation_error(args, log, out_dir):
    relations = os.path.join(args.data, log, f"{log}.relations")
    return run_json([args.slam2d, "eval", os.path.join(out_dir, "trajectory.txt"), "--relations", relations, "--json"])["trans_mean"]


def map_run(args, log, source, name, method, options, seed=1):
    out_dir = os.path.join(args.out, f"{log}_{name}_{method}_{seed}")
    command = [args.slam2d, "map", source, "--method", method, "--seed", str(seed), "--trajectory-frame", "sensor",
               "--out", out_dir, "--quiet", "--json"] + options
    summary = run_json(command)
    return summary["scans"], relation_error(args, log, out_dir), os.path.join(out_dir, "trajectory.txt"), " ".join(command)


def read_seconds(args, source, options):
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        subprocess.run([args.slam2d, "info", source, "--json"] + options, check=True, capture_output=True)
        best = min(best, time.perf_counter() - start)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--logs", nargs="+", default=LOGS)
    parser.add_argument("--out", default="/tmp/slam2d_bag_benchmark")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for log in args.logs:
        found = sources(args.data, log, os.path.join(args.out, "unpacked"))
        geometry = ["--fov", "180"] if log == "intel" else []
        variants = [("carmen", "carmen", [])]
        for kind in ("ros1", "mcap", "db3"):
            if kind in found:
                variants.append((kind, kind, geometry))
        variants.append(("ros1 latest", "ros1", geometry + ["--scan-odometry", "latest"]))
        graph_trajectories = {}
        for name, kind, options in variants:
            tag = name.replace(" ", "_")
            scans, graph, trajectory, command = map_run(args, log, found[kind], tag, "graph", options)
            with open(trajectory, "rb") as f:
                graph_trajectories[name] = f.read()
            rbpf = []
            if kind in ("carmen", "ros1"):  # the ROS 2 formats give the ROS 1 bag's trajectories (checked on graph)
                rbpf = [map_run(args, log, found[kind], tag, "rbpf", options, seed)[1] for seed in range(1, args.seeds + 1)]
            rows.append({
                "log": log, "source": name, "options": " ".join(options), "scans": scans, "graph_m": graph,
                "rbpf_median_m": statistics.median(rbpf) if rbpf else None,
                "rbpf_min_m": min(rbpf) if rbpf else None, "rbpf_max_m": max(rbpf) if rbpf else None,
                "read_s": read_seconds(args, found[kind], options), "graph_command": command,
            })
        formats = [name for name in ("ros1", "mcap", "db3") if name in graph_trajectories]
        for row in rows:
            if row["log"] == log and row["source"] in formats:
                row["same_as_ros1"] = graph_trajectories[row["source"]] == graph_trajectories["ros1"]
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    print(f"| log | source | options | scans | graph (m) | rbpf median [min, max] over {args.seeds} seeds (m) | "
          "graph trajectory = ros1's | read (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        rbpf = f"{r['rbpf_median_m']:.4f} [{r['rbpf_min_m']:.4f}, {r['rbpf_max_m']:.4f}]" if r["rbpf_median_m"] else "-"
        same = {True: "yes", False: "NO"}.get(r.get("same_as_ros1"), "-")
        print(f"| {r['log']} | {r['source']} | {r['options'] or '-'} | {r['scans']} | {r['graph_m']:.4f} | {rbpf} | {same} | "
              f"{r['read_s']:.3f} |")


if __name__ == "__main__":
    main()
