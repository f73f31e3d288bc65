#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The Python API's cost over C++ (issue 23's figures).

1. Per call: slam2d.match(target, source, guess, method="pl-icp") on two 360-beam scans of a
   simulated room, against the same match looped in C++ (_slam2d._time_match: clouds and matcher
   made once). The Python call builds the matcher each time and, given arrays, copies them into
   clouds; given slam2d.Cloud objects (made once), it copies nothing.
2. Graph SLAM on a log: slam2d.map_log against `slam2d map`, CPU seconds of the mapping job
   (summary.json's cpu_s) and the process's CPU time.

Usage: PYTHONPATH=build/release/python bench/python/python_overhead.py [--log LOG] [--slam2d build/release/bin/slam2d]
"""

import argparse
import json
import math
import os
import resource
import subprocess
import tempfile
import time

import numpy as np

import slam2d
from slam2d import _slam2d


def room_scan(pose, beams=360):
    """End points of a 360-beam scan from `pose` in a 10 x 6 m room with a pillar."""
    points = []
    for a in np.linspace(-math.pi, math.pi, beams, endpoint=False):
        d = np.array([math.cos(a + pose.theta), math.sin(a + pose.theta)])
        o = np.array([pose.x, pose.y])
        best = min(t for axis, wall in ((0, 5.0), (0, -5.0), (1, 3.0), (1, -3.0))
                   if abs(d[axis]) > 1e-9 and (t := (wall - o[axis]) / d[axis]) > 0)
        q = o - [2.0, 1.0]
        b, c = q @ d, q @ q - 0.16
        if b * b - c > 0 and -b - math.sqrt(b * b - c) > 0:
            best = min(best, -b - math.sqrt(b * b - c))
        points.append([best * math.cos(a), best * math.sin(a)])
    return np.array(points)


def per_call(method, repeats):
    target = room_scan(slam2d.SE2(0.5, 0.3, 0.0))
    source = room_scan(slam2d.SE2(0.62, 0.23, 0.04))
    guess = slam2d.SE2()
    cpp = min(_slam2d._time_match(target, source, guess, method, repeats) for _ in range(5))

    def best_of(a, b):
        best = math.inf
        for _ in range(5):
            start = time.perf_counter()
            for _ in range(repeats):
                slam2d.match(a, b, guess, method=method)
            best = min(best, (time.perf_counter() - start) / repeats)
        return best
    return cpp, best_of(target, source), best_of(slam2d.Cloud(target), slam2d.Cloud(source))


def graph_cpu(log, cli):
    with tempfile.TemporaryDirectory() as folder:
        before = resource.getrusage(resource.RUSAGE_SELF)
        run = slam2d.map_log(log, method="graph", out=os.path.join(folder, "python"))
        after = resource.getrusage(resource.RUSAGE_SELF)
        python_process = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        summary = json.loads(subprocess.run([cli, "map", log, "--method", "graph", "--out", os.path.join(folder, "cli"),
                                             "--quiet", "--json"], check=True, capture_output=True, text=True).stdout)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cli_process = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        return run.summary["cpu_s"], python_process, summary["cpu_s"], cli_process


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--log", default=os.path.join(os.environ.get("SLAM2D_DATA", "/work/shared/data"), "intel", "intel.clf.gz"))
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--repeats", type=int, default=200)
    args = parser.parse_args()
    cpp, arrays, clouds = per_call("pl-icp", args.repeats)
    print(f"pl-icp, 360 beams: C++ {cpp * 1e6:.1f} us/call; Python with arrays {arrays * 1e6:.1f} us/call "
          f"(+{100 * (arrays / cpp - 1):.1f}%), with Clouds {clouds * 1e6:.1f} us/call (+{100 * (clouds / cpp - 1):.1f}%)")
    job_py, process_py, job_cli, process_cli = graph_cpu(args.log, args.slam2d)
    print(f"graph SLAM on {os.path.basename(args.log)}: job CPU {job_py:.2f} s from Python, {job_cli:.2f} s from the CLI; "
          f"process CPU {process_py:.2f} s vs {process_cli:.2f} s")


if __name__ == "__main__":
    main()
