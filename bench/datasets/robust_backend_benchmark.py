#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Robust pose-graph back ends on graphs spoiled with false loop closures (issue 41, item 3): the
comparison of Suenderhauf and Protzel (switchable constraints, IROS 2012), Agarwal et al. (DCS,
ICRA 2013) and Yang et al. (GNC, RA-L 2020), on Vertigo's graphs.

For each graph, false share, placement and seed: `slam2d spoil` adds the false loop edges,
`slam2d optimize --robust KERNEL --outliers-from FIRST_FALSE --json` runs each back end, and the
optimised nodes are scored against the outlier-free optimum (`slam2d optimize --gate none` of the clean graph):
ATE, the root mean square position difference after a rigid 2D alignment (m); the precision and
recall of the loop edges the back end keeps (robust weight >= 0.5); its CPU time. A run that takes
longer than --timeout seconds is reported as such (random false closures across a large graph fill
the sparse factor in). Results are cached in --out, so a second run only adds what is missing.

    /usr/bin/python3 bench/datasets/robust_backend_benchmark.py --jobs 2
"""

import argparse
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from common import CommandFailed, run_json, write_atomic

GRAPHS = {
    "manhattan": "posegraphs/vertigo/manhattanOlson3500.g2o",
    "intel": "posegraphs/vertigo/intel.g2o",
    "city10000": "posegraphs/se-sync/city10000.g2o",
    "ring": "posegraphs/vertigo/ring.g2o",
    "ringcity": "posegraphs/vertigo/ringCity.g2o",
}
# A back end is KERNEL:SCALE, slam2d optimize --robust KERNEL --robust-scale SCALE (tls: GNC), on
# every edge (--gate none); KERNEL:SCALE+gate behind the pairwise consistency gate (--gate pairs).
BACK_ENDS = ["none:1", "cauchy:1", "dcs:1", "tls:1", "tls:2", "tls:3",
             "none:1+gate", "dcs:1+gate", "tls:2+gate"]


def back_end_arguments(back_end):
    kernel_scale, _, gate = back_end.partition("+")
    kernel, _, scale = kernel_scale.partition(":")
    return ["--robust", kernel, "--robust-scale", scale or "1", "--gate", "pairs" if gate == "gate" else "none"]


def read_positions(path):
    """The (x, y) of each VERTEX_SE2 of a g2o file, by id."""
    positions = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            fields = line.split()
            if fields and fields[0] == "VERTEX_SE2":
                positions[int(fields[1])] = (float(fields[2]), float(fields[3]))
    return positions


def aligned_rmse(estimate, reference):
    """Root mean square distance of the common nodes after the rigid 2D alignment (Umeyama, no scale)."""
    ids = sorted(set(estimate) & set(reference))
    a = np.array([estimate[i] for i in ids])
    b = np.array([reference[i] for i in ids])
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((b - cb).T @ (a - ca))
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    rotation = u @ d @ vt
    moved = (a - ca) @ rotation.T + cb
    return float(math.sqrt(np.mean(np.sum((moved - b) ** 2, axis=1))))


def cached(path, compute):
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    value = compute()
    write_atomic(path, json.dumps(value))
    return value


def run_case(args, graph, share, placement, seed, back_end):
    folder = os.path.join(args.out, graph)
    os.makedirs(folder, exist_ok=True)
    source = os.path.join(args.data, GRAPHS[graph])
    reference = os.path.join(folder, "reference.g2o")
    if not os.path.exists(reference):
        run_json([args.slam2d, "optimize", source, "--out", reference, "--gate", "none", "--json"])
    tag = f"{placement}_{share}_s{seed}"
    spoiled = os.path.join(folder, f"{tag}.g2o")
    spoil = cached(os.path.join(folder, f"{tag}.spoil.json"), lambda: run_json(
        [args.slam2d, "spoil", source, "--out", spoiled, "--share", str(share), "--placement", placement,
         "--seed", str(seed), "--json"]))

    def optimise():
        out = os.path.join(folder, f"{tag}.{back_end}.g2o")
        command = [args.slam2d, "optimize", spoiled, "--out", out, "--json",
                   "--outliers-from", str(spoil["first_false_edge"]), *back_end_arguments(back_end)]
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=args.timeout)
        except subprocess.TimeoutExpired:
            return {"timeout": args.timeout}
        if done.returncode != 0:
            raise CommandFailed(f"{' '.join(command)} failed: {done.stderr.strip()[-2000:]}")
        summary = json.loads(done.stdout)
        summary["ate"] = aligned_rmse(read_positions(out), read_positions(reference))
        os.remove(out)
        return summary

    return cached(os.path.join(folder, f"{tag}.{back_end}.json"), optimise)


def cell(result):
    if "timeout" in result:
        return f"> {result['timeout']:.0f} s"
    return (f"{result['ate']:.2g} / {result['precision']:.3f} / {result['recall']:.3f} / "
            f"{result['cpu_s']:.2g} s")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--graphs", nargs="+", default=list(GRAPHS), choices=list(GRAPHS))
    parser.add_argument("--shares", nargs="+", type=float, default=[0.1, 0.2, 0.5])
    parser.add_argument("--placements", nargs="+", default=["random", "local-grouped"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[1])
    parser.add_argument("--back-ends", nargs="+", default=BACK_ENDS, help="KERNEL:SCALE of slam2d optimize --robust")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds a back end may take on one graph")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--out", default="/tmp/slam2d_robust_backends")
    parser.add_argument("--json", action="store_true", help="print every result as JSON instead of the table")
    args = parser.parse_args()

    cases = [(g, share, placement, seed, b) for g in args.graphs for share in args.shares
             for placement in args.placements for seed in args.seeds for b in args.back_ends]
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(lambda case: run_case(args, *case), cases))
    table = dict(zip(cases, results))
    if args.json:
        print(json.dumps([{"graph": c[0], "share": c[1], "placement": c[2], "seed": c[3], "back_end": c[4], **r}
                          for c, r in table.items()]))
        return 0
    print("ATE against the outlier-free optimum (m) / precision / recall of the loop edges kept / CPU time\n")
    print("| graph | false share | placement | seed | " + " | ".join(args.back_ends) + " |")
    print("|---|---|---|---|" + "---|" * len(args.back_ends))
    for g in args.graphs:
        for share in args.shares:
            for placement in args.placements:
                for seed in args.seeds:
                    cells = [cell(table[(g, share, placement, seed, b)]) for b in args.back_ends]
                    print(f"| {g} | {share:g} | {placement} | {seed} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
