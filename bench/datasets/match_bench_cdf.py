#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The error distributions of `slam2d match-bench --out DIR` as cumulative distribution plots.

Reads DIR/cases.csv (one row per match: matcher, level, pair, ..., trans_error, rot_error_deg,
success) and draws, per perturbation level, the CDF of the translation error (top row) and of the
rotation error (bottom row), one curve per matcher, as Pomerleau et al. 2013 report them. The
success thresholds are drawn as dashed lines when given.

Usage: bench/datasets/match_bench_cdf.py DIR/cases.csv --out FIGURE.png|.svg [--title TEXT]
                                          [--success-trans 0.1] [--success-rot 2] [--dpi 72]
"""

import argparse
import csv
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

REQUIRED = ("matcher", "level", "sigma_trans", "sigma_rot_deg", "trans_error", "rot_error_deg")


def read_cases(path):
    """{level: {matcher: (trans errors, rot errors)}}, levels and matchers in file order."""
    with open(path, newline="") as stream:
        reader = csv.DictReader(stream)
        missing = [c for c in REQUIRED if c not in (reader.fieldnames or [])]
        if missing:
            sys.exit(f"{path}: not a match-bench cases.csv (missing columns {', '.join(missing)})")
        cases = {}
        for line, row in enumerate(reader, start=2):
            try:
                trans, rot = float(row["trans_error"]), float(row["rot_error_deg"])
            except (TypeError, ValueError):
                sys.exit(f"{path}:{line}: trans_error / rot_error_deg are not numbers")
            level = (row["level"], float(row["sigma_trans"]), float(row["sigma_rot_deg"]))
            errors = cases.setdefault(level, {}).setdefault(row["matcher"], ([], []))
            errors[0].append(trans)
            errors[1].append(rot)
    if not cases:
        sys.exit(f"{path}: no cases")
    return cases


def cdf(values):
    x = np.sort(np.asarray(values, dtype=float))
    return x, np.arange(1, len(x) + 1) / len(x)


def draw(cases, title, success_trans, success_rot):
    levels = list(cases)
    matchers = list(dict.fromkeys(m for level in levels for m in cases[level]))
    colours = {m: plt.get_cmap("tab10")(i % 10) for i, m in enumerate(matchers)}
    figure, axes = plt.subplots(2, len(levels), figsize=(3.2 * len(levels) + 1.6, 5.4), squeeze=False,
                                sharey=True, sharex="row")
    floor = 1e-4  # errors of 0 (exact matches) are drawn at the axis' left end
    for column, level in enumerate(levels):
        name, sigma_t, sigma_r = level
        for row, (unit, threshold) in enumerate((("m", success_trans), ("deg", success_rot))):
            ax = axes[row][column]
            for matcher in matchers:
                if matcher not in cases[level]:
                    continue
                x, y = cdf(np.maximum(cases[level][matcher][row], floor))
                ax.step(x, y, where="post", color=colours[matcher], linewidth=1.2, label=matcher)
            if threshold:
                ax.axvline(threshold, color="0.4", linestyle="--", linewidth=0.8)
            ax.set_xscale("log")
            ax.grid(True, which="major", linewidth=0.4, alpha=0.5)
            ax.set_xlabel(("translation" if row == 0 else "rotation") + f" error ({unit})", fontsize=8)
            ax.tick_params(labelsize=7)
            if row == 0:
                ax.set_title(f"guess sigma {sigma_t:g} m, {sigma_r:g} deg", fontsize=9)
            if column == 0:
                ax.set_ylabel("share of pairs", fontsize=8)
    axes[0][-1].legend(fontsize=7, loc="lower right", frameon=True)
    if title:
        figure.suptitle(title, fontsize=10)
    figure.tight_layout()
    return figure


def save_atomically(figure, path, dpi):
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    suffix = os.path.splitext(path)[1] or ".png"
    handle, temporary = tempfile.mkstemp(dir=folder, suffix=suffix)
    os.close(handle)
    try:
        figure.savefig(temporary, dpi=dpi, metadata={"Software": None} if suffix == ".png" else {"Date": None})
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("cases", help="cases.csv written by slam2d match-bench --out DIR")
    parser.add_argument("--out", required=True, help="figure to write (.png or .svg)")
    parser.add_argument("--title", default="")
    parser.add_argument("--success-trans", type=float, default=0.1, help="m, drawn as a dashed line (0: none)")
    parser.add_argument("--success-rot", type=float, default=2.0, help="deg, drawn as a dashed line (0: none)")
    parser.add_argument("--dpi", type=int, default=72)
    args = parser.parse_args()
    if not os.path.isfile(args.cases):
        sys.exit(f"{args.cases}: no such file")
    figure = draw(read_cases(args.cases), args.title, args.success_trans, args.success_rot)
    save_atomically(figure, args.out, args.dpi)


if __name__ == "__main__":
    main()
