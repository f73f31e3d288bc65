# SPDX-License-Identifier: BSD-3-Clause
"""The examples in examples/python run, and the 2015 study's grid holds 20 configurations the C++
field tables accept."""

import os
import subprocess
import sys

import pytest
import yaml

import slam2d

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLES = os.path.join(ROOT, "examples", "python")
CLI = os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d")


def test_the_2015_grid_is_20_valid_graph_configurations():
    with open(os.path.join(EXAMPLES, "grid_2015.yaml"), encoding="utf-8") as f:
        grid = yaml.safe_load(f)
    assert len(grid["graph"]) == 20
    for name, fields in grid["graph"].items():
        slam2d.GraphSlam(fields)  # an unknown or out-of-range field would be an Error


@pytest.mark.parametrize("script, extra", [("match_two_scans.py", ["--out"]), ("map_a_log.py", ["--out"]),
                                           ("compare_methods.py", [])])
def test_an_example_runs(script, extra, tmp_path):
    pytest.importorskip("matplotlib")
    log = str(tmp_path / "office.clf")
    subprocess.run([CLI, "simulate", "--quiet", "--duration", "30", "--seed", "5", "--out", log], check=True)
    arguments = [sys.executable, os.path.join(EXAMPLES, script), log] + extra
    if extra:
        arguments.append(str(tmp_path / "out.png"))
    result = subprocess.run(arguments, capture_output=True, text=True, env=dict(os.environ))
    assert result.returncode == 0, result.stderr
    if extra:
        assert os.path.getsize(tmp_path / "out.png") > 10000
