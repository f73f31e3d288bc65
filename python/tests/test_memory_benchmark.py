# SPDX-License-Identifier: BSD-3-Clause
"""bench/datasets/memory_benchmark.py on a simulated log (issue 25, "Memory over long runs"): the
peak memory it reads is the child's own (a large child is measured large, a small one small, whatever
ran before), and a replay of P passes gives graph SLAM P times the keyframes, of which the lifelong
budget (the default; off in configs/graph-keep-all.yaml) releases most of the new ones."""

import importlib.util
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CLI = os.environ.get("SLAM2D_BIN", os.path.join(ROOT, "build", "release", "bin", "slam2d"))
SCRIPT = os.path.join(ROOT, "bench", "datasets", "memory_benchmark.py")
sys.path.insert(0, os.path.join(ROOT, "bench", "datasets"))
spec = importlib.util.spec_from_file_location("memory_benchmark", SCRIPT)
bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench)
from common import CommandFailed  # noqa: E402 (bench/datasets is on the path from here on)


def test_the_peak_is_the_childs_own():
    python = sys.executable
    _, big = bench.run_measured([python, "-c", "b = bytearray(300 * 2**20); b[::4096] = b'x' * len(b[::4096])"])
    _, small = bench.run_measured([python, "-c", "pass"])  # after the big child: not its maximum
    assert big > 300
    assert small < 100


def test_a_failing_command_names_itself():
    try:
        bench.run_measured([CLI, "map", "/nonexistent.clf", "--method", "odometry", "--out", "/tmp/x"])
    except CommandFailed as e:
        assert "/nonexistent.clf" in str(e)
    else:
        raise AssertionError("no CommandFailed")


def test_a_replay_multiplies_graph_keyframes_and_the_budget_releases_revisits(tmp_path):
    data = tmp_path / "data"
    (data / "sim").mkdir(parents=True)
    subprocess.run([CLI, "simulate", "--out", str(data / "sim" / "sim.clf"), "--duration", "60", "--seed", "2",
                    "--quiet"], check=True)
    out = tmp_path / "out"
    result = subprocess.run([sys.executable, SCRIPT, "--slam2d", CLI, "--data", str(data), "--logs", "sim",
                             "--passes", "1", "3", "--methods", "odometry", "graph", "graph-keep-all", "ekf",
                             "--out", str(out), "--json", "--quiet"], capture_output=True, text=True, check=True)
    assert result.stderr == ""  # --quiet: no progress line
    rows = {row["method"]: row["passes"] for row in json.loads(result.stdout)}
    assert json.loads((out / "memory.json").read_text()) == json.loads(result.stdout)
    assert set(rows) == {"odometry", "graph", "graph-keep-all", "ekf"}
    for passes in rows.values():
        assert 1 < passes["1"]["peak_mb"] < 2000
    keep_all = rows["graph-keep-all"]
    assert 2.5 * keep_all["1"]["keyframes"] <= keep_all["3"]["keyframes"] <= 3.5 * keep_all["1"]["keyframes"]
    assert keep_all["3"]["released_keyframes"] == 0
    lifelong = rows["graph"]["3"]  # the default: the lifelong keyframe budget on
    assert lifelong["released_keyframes"] > 0.6 * (lifelong["keyframes"] - keep_all["1"]["keyframes"])
