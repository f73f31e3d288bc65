#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Independent reference implementation of the relation-based SLAM error metric of

    R. Kuemmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti, C. Stachniss, A. Kleiner:
    "On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4), 2009, Sec. 3.

It is written from the paper's definition with 3x3 homogeneous matrices and the Python standard
library only, to cross-check slam2d's C++ implementation (src/slam2d/eval/relation_error.cpp).

For each ground-truth relation (t1, t2, delta*) -- the pose at t2 in the frame of the pose at t1 --
the trajectory poses X1, X2 nearest in time to t1 and t2 (within the tolerance; on an exact tie
the earlier stamp wins) give the estimated relation delta = X1^-1 X2, and the error is
delta (-) delta* = delta*^-1 delta. Its translational error is the length of its translation (m),
its rotational error the absolute value of its angle (reported in degrees). A relation with a
stamp that has no pose within the tolerance is counted as missing and left out.

Inputs:
  trajectory  text, one pose per line: "t x y theta" (s, m, m, rad); '#' comments, blank lines.
  relations   text, one relation per line: "t1 t2 x y z roll pitch yaw" (s, m, rad); z, roll and
              pitch are ignored.

Output: one JSON object on stdout with relations, missing, trans_mean, trans_std, trans_max,
rot_mean_deg, rot_std_deg, rot_max_deg, trans_sq_mean, rot_sq_mean_deg2. Standard deviations are
population ones (divide by N). All statistics are 0 when no relation was evaluated.
Exit status 2 on unreadable or malformed input.

Usage: relation_error_reference.py TRAJECTORY RELATIONS [--tolerance SECONDS]
"""

import argparse
import bisect
import json
import math
import statistics
import sys


class InputError(Exception):
    pass


def read_rows(path, columns):
    """The numeric rows of a whitespace-separated text file, with their 1-based line numbers."""
    rows = []
    try:
        with open(path, "r", encoding="utf-8") as handle:
            for number, line in enumerate(handle, start=1):
                text = line.strip()
                if not text or text.startswith("#"):
                    continue
                fields = text.split()
                if len(fields) != columns:
                    raise InputError(f"{path}:{number}: expected {columns} numbers, got {len(fields)}")
                try:
                    values = [float(f) for f in fields]
                except ValueError:
                    raise InputError(f"{path}:{number}: not a number") from None
                if not all(math.isfinite(v) for v in values):
                    raise InputError(f"{path}:{number}: non-finite value")
                rows.append(values)
    except OSError as error:
        raise InputError(f"{path}: cannot read: {error.strerror}") from None
    return rows


def homogeneous(x, y, theta):
    """The 3x3 matrix of the rigid motion (x, y, theta)."""
    c, s = math.cos(theta), math.sin(theta)
    return [[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]]


def multiply(a, b):
    return [[sum(a[r][k] * b[k][col] for k in range(3)) for col in range(3)] for r in range(3)]


def invert_rigid(m):
    """[R t; 0 1]^-1 = [R^T -R^T t; 0 1]."""
    rt = [[m[0][0], m[1][0]], [m[0][1], m[1][1]]]
    tx = -(rt[0][0] * m[0][2] + rt[0][1] * m[1][2])
    ty = -(rt[1][0] * m[0][2] + rt[1][1] * m[1][2])
    return [[rt[0][0], rt[0][1], tx], [rt[1][0], rt[1][1], ty], [0.0, 0.0, 1.0]]


class NearestStamp:
    """Finds the pose whose stamp is nearest to a query stamp, whatever the file order."""

    def __init__(self, stamps):
        order = sorted(range(len(stamps)), key=lambda i: stamps[i])
        self.stamps = [stamps[i] for i in order]
        self.indices = order

    def find(self, stamp, tolerance):
        position = bisect.bisect_left(self.stamps, stamp)
        candidates = [p for p in (position - 1, position) if 0 <= p < len(self.stamps)]
        if not candidates:
            return None
        # Nearest first; on an exact tie the earlier stamp (smaller position) wins.
        best = min(candidates, key=lambda p: (abs(self.stamps[p] - stamp), p))
        if abs(self.stamps[best] - stamp) > tolerance:
            return None
        return self.indices[best]


def relation_errors(poses, relations, tolerance):
    """(translational errors in m, rotational errors in rad, number of missing relations)."""
    index = NearestStamp([p[0] for p in poses])
    matrices = [homogeneous(x, y, theta) for _, x, y, theta in poses]
    translation, rotation, missing = [], [], 0
    for t1, t2, x, y, _z, _roll, _pitch, yaw in relations:
        i, j = index.find(t1, tolerance), index.find(t2, tolerance)
        if i is None or j is None:
            missing += 1
            continue
        estimated = multiply(invert_rigid(matrices[i]), matrices[j])  # delta = X1^-1 X2
        error = multiply(invert_rigid(homogeneous(x, y, yaw)), estimated)  # delta*^-1 delta
        translation.append(math.hypot(error[0][2], error[1][2]))
        rotation.append(abs(math.atan2(error[1][0], error[0][0])))
    return translation, rotation, missing


def mean_std_max(values):
    if not values:
        return 0.0, 0.0, 0.0
    return statistics.fmean(values), statistics.pstdev(values), max(values)


def evaluate(trajectory_path, relations_path, tolerance):
    poses = read_rows(trajectory_path, 4)
    relations = read_rows(relations_path, 8)
    translation, rotation, missing = relation_errors(poses, relations, tolerance)
    rotation_deg = [math.degrees(r) for r in rotation]
    trans_mean, trans_std, trans_max = mean_std_max(translation)
    rot_mean, rot_std, rot_max = mean_std_max(rotation_deg)
    return {
        "relations": len(translation),
        "missing": missing,
        "trans_mean": trans_mean,
        "trans_std": trans_std,
        "trans_max": trans_max,
        "rot_mean_deg": rot_mean,
        "rot_std_deg": rot_std,
        "rot_max_deg": rot_max,
        "trans_sq_mean": mean_std_max([t * t for t in translation])[0],
        "rot_sq_mean_deg2": mean_std_max([r * r for r in rotation_deg])[0],
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trajectory", help='trajectory text file, "t x y theta" per line')
    parser.add_argument("relations", help='relations file, "t1 t2 x y z roll pitch yaw" per line')
    parser.add_argument("--tolerance", type=float, default=0.001,
                        help="stamp matching tolerance in seconds (default 0.001)")
    args = parser.parse_args()
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0.0):
        print("error: --tolerance must be finite and >= 0", file=sys.stderr)
        return 2
    try:
        result = evaluate(args.trajectory, args.relations, args.tolerance)
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
