# SPDX-License-Identifier: BSD-3-Clause
"""The helpers of bench/datasets/pipeline_benchmark.py on hand-made files: the short relations
(the true local error) and the paired difference of two runs' errors on them."""

import importlib.util
import math
import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "bench", "datasets"))  # as when the script runs: its `common` beside it
spec = importlib.util.spec_from_file_location("pipeline_benchmark", os.path.join(ROOT, "bench", "datasets", "pipeline_benchmark.py"))
bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench)


def test_short_relations_keep_those_spanning_at_most_the_limit_either_way(tmp_path):
    relations = tmp_path / "r.relations"
    relations.write_text("10.0 10.5 0.1 0 0 0 0 0\n"
                         "10.0 11.0 0.2 0 0 0 0 0\n"   # exactly 1 s: kept
                         "12.0 10.9 0.3 0 0 0 0 0\n"   # backwards, 1.1 s: dropped
                         "20.0 20.2 0.4 0 0 0 0 0\n"
                         "20.0 40.0 0.5 0 0 0 0 0\n")
    out = tmp_path / "short.relations"
    assert bench.short_relations(str(relations), str(out), 1.0) == 3
    assert [line.split()[2] for line in out.read_text().splitlines()] == ["0.1", "0.2", "0.4"]


def write_errors(path, rows):
    with open(path, "w") as f:
        f.write("stamp_from,stamp_to,x_from,y_from,x_to,y_to,translation_m,rotation_deg\n")
        for t0, t1, e in rows:
            f.write(f"{t0},{t1},0,0,0,0,{e},0\n")


def test_paired_difference_pairs_the_same_relations_and_gives_the_standard_error(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    write_errors(a, [(1, 2, 0.03), (2, 3, 0.05), (3, 4, 0.02), (5, 6, 9.0)])  # (5, 6) only in a: not paired
    write_errors(b, [(2, 3, 0.04), (1, 2, 0.01), (3, 4, 0.03)])
    d = bench.paired_difference(str(a), str(b))
    assert d["relations"] == 3
    assert d["mean"] == pytest.approx((0.02 + 0.01 - 0.01) / 3)
    sd = math.sqrt(sum((x - 0.02 / 3) ** 2 for x in (0.02, 0.01, -0.01)) / 2)
    assert d["se"] == pytest.approx(sd / math.sqrt(3))
    write_errors(b, [(1, 2, 0.01)])
    assert math.isnan(bench.paired_difference(str(a), str(b))["mean"])  # one pair: no spread
