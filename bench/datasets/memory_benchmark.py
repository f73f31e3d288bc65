#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Memory benchmark: peak memory of every method over one pass of a log and over the log replayed
(docs/reliability.md, "Memory over long runs"; issue 25).

For each log and each pass count P in --passes (1 is the log itself):
    slam2d perturb LOG --out REPLAY --fault repeat:times=P,back=1 --quiet     (P > 1; --end-to-end: back=0)
    slam2d map REPLAY --method M --out DIR --quiet --json                      (M in --methods)
    slam2d localize REPLAY --map GRAPH_OF_ONE_PASS/map.yaml --method mcl|ekf --initial=0,0,0 --out T --quiet
and the peak resident memory of each command (the child's own maximum RSS, from wait4).
'graph-keep-all' is graph SLAM with configs/graph-keep-all.yaml (the lifelong keyframe budget off).
Prints a markdown table: peak MB per pass count and the ratio of the last to one pass; for graph
SLAM also its keyframes and those released. --json prints one JSON document instead.

Usage: bench/datasets/memory_benchmark.py [--slam2d build/release/bin/slam2d] [--data $SLAM2D_DATA]
           [--logs intel fr079] [--passes 1 10] [--methods odometry hector graph graph-keep-all rbpf
           hector+graph mcl ekf] [--end-to-end] [--out /tmp/slam2d_memory] [--json] [--quiet]
A log is $SLAM2D_DATA/LOG/LOG.clf.gz (or .clf).
Ten passes of Intel and FR079 with every method: about 50 minutes on one core (graph SLAM's ten
passes of Intel alone 8 minutes, 13 with graph-keep-all: its back end optimises the whole graph
after every closure).
"""

import argparse
import json
import os
import sys

from common import run, run_measured, write_atomic

LOGS = ["intel", "fr079"]
METHODS = ["odometry", "hector", "graph", "graph-keep-all", "rbpf", "hector+graph", "mcl", "ekf"]
LOCALIZERS = {"mcl", "ekf"}
HERE = os.path.dirname(os.path.abspath(__file__))
KEEP_ALL = os.path.join(HERE, "..", "..", "configs", "graph-keep-all.yaml")


def replay(args, log, passes):
    """The log played `passes` times (back and forth unless --end-to-end)."""
    source = os.path.join(args.data, log, f"{log}.clf.gz")
    if not os.path.exists(source):
        source = source[:-len(".gz")]
    if passes == 1:
        return source
    path = os.path.join(args.out, f"{log}x{passes}.clf")
    if not os.path.exists(path):
        back = 0 if args.end_to_end else 1
        run([args.slam2d, "perturb", source, "--out", path, "--fault", f"repeat:times={passes},back={back}", "--quiet"])
    return path


def measure(args, log, passes, method):
    """One run: {'peak_mb': ..., and for graph SLAM 'keyframes', 'released_keyframes'}."""
    source = replay(args, log, passes)
    out = os.path.join(args.out, f"{log}x{passes}-{method}")
    if method in LOCALIZERS:
        one_pass_map = os.path.join(args.out, f"{log}x1-graph", "map.yaml")
        if not os.path.exists(one_pass_map):
            run([args.slam2d, "map", replay(args, log, 1), "--method", "graph", "--out", os.path.dirname(one_pass_map), "--quiet"])
        command = [args.slam2d, "localize", source, "--map", one_pass_map, "--method", method, "--initial=0,0,0",
                   "--out", out + ".txt", "--quiet"]
        _, peak = run_measured(command)
        return {"peak_mb": peak}
    config = ["--method", "graph", "--config", KEEP_ALL] if method == "graph-keep-all" else ["--method", method]
    stdout, peak = run_measured([args.slam2d, "map", source, *config, "--out", out, "--quiet", "--json"])
    summary = json.loads(stdout)
    result = {"peak_mb": peak}
    for key in ("keyframes", "released_keyframes"):  # graph SLAM's, and hector+graph's (its sparse graph)
        if key in summary:
            result[key] = summary[key]
    return result


def table(results, passes):
    lines = ["| log | method | " + " | ".join(f"{p} pass{'es' if p > 1 else ''}" for p in passes) +
             f" | {passes[-1]} / {passes[0]} | keyframes (released) |",
             "|---|---|" + "---|" * (len(passes) + 2)]
    for (log, method), by_passes in results.items():
        peaks = [by_passes[p]["peak_mb"] for p in passes]
        last = by_passes[passes[-1]]
        keyframes = (f"{last['keyframes']} ({last.get('released_keyframes', 0)})" if "keyframes" in last else "-")
        lines.append(f"| {log} | {method} | " + " | ".join(f"{v:.0f} MB" for v in peaks) +
                     f" | {peaks[-1] / peaks[0]:.2f} | {keyframes} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--slam2d", default="build/release/bin/slam2d")
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--logs", nargs="+", default=LOGS)
    parser.add_argument("--passes", nargs="+", type=int, default=[1, 10])
    parser.add_argument("--methods", nargs="+", default=METHODS, choices=METHODS)
    parser.add_argument("--end-to-end", action="store_true", help="replay end to end (teleports) instead of back and forth")
    parser.add_argument("--out", default="/tmp/slam2d_memory")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--quiet", action="store_true", help="no progress line")
    args = parser.parse_args()
    if any(p < 1 for p in args.passes):
        parser.error("--passes: each at least 1")
    passes = sorted(set(args.passes))
    os.makedirs(args.out, exist_ok=True)
    results = {}
    for log in args.logs:
        for method in args.methods:
            for p in passes:
                if not args.quiet:
                    print(f"\r{log} {method} x{p} ...".ljust(60), end="", file=sys.stderr, flush=True)
                results.setdefault((log, method), {})[p] = measure(args, log, p, method)
    if not args.quiet:
        print("\r".ljust(60), file=sys.stderr)
    document = [{"log": log, "method": method, "passes": {str(p): r for p, r in by.items()}}
                for (log, method), by in results.items()]
    write_atomic(os.path.join(args.out, "memory.json"), json.dumps(document, indent=1) + "\n")
    print(json.dumps(document, indent=1) if args.json else table(results, passes))


if __name__ == "__main__":
    main()
