#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Compare SLAM methods on logs with relations: error, CPU time, one row per (log, method).

    PYTHONPATH=build/release/python examples/python/compare_methods.py LOG... [--methods hector,graph,rbpf]

Each LOG needs LOG's NAME.relations beside it (intel.clf.gz -> intel.relations). For many logs,
methods and configurations on a cluster, see python3 -m slam2d.sweep.
"""
import argparse
import os

import slam2d
from slam2d.sweep import find_relations, log_name

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("logs", nargs="+")
parser.add_argument("--methods", default="hector,graph,rbpf")
args = parser.parse_args()

print(f"| log | method | trans_mean (m) | rot_mean (deg) | CPU (s) |")
print("|---|---|---|---|---|")
for log in args.logs:
    relations = find_relations(log, None)
    for method in args.methods.split(","):
        run = slam2d.map_log(log, method=method)
        error = slam2d.relation_error(run.trajectory, relations) if relations else {"trans_mean": float("nan"), "rot_mean_deg": float("nan")}
        print(f"| {log_name(log)} | {method} | {error['trans_mean']:.4f} | {error['rot_mean_deg']:.3f} | {run.summary['cpu_s']:.2f} |")
