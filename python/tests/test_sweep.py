# SPDX-License-Identifier: BSD-3-Clause
"""slam2d.sweep on a Dask LocalCluster: every task gives a row; a worker killed mid-sweep loses no
task; a rerun skips what is done; a failing task is reported without stopping the others."""

import os
import signal
import subprocess

import pytest

distributed = pytest.importorskip("distributed")

from slam2d import sweep  # noqa: E402

CLI = os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d")


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    paths = []
    for seed in (3, 4):
        path = str(folder / f"office{seed}.clf")
        subprocess.run([CLI, "simulate", "--quiet", "--duration", "120", "--seed", str(seed), "--out", path], check=True)
        paths.append(path)
    return paths


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_a_worker_killed_mid_sweep_loses_nothing_and_a_rerun_skips_what_is_done(logs, client, tmp_path):
    tasks = sweep.make_tasks(logs, ["graph", "hector"], {}, None, str(tmp_path))
    assert len(tasks) == 4
    workers = sorted(client.run(os.getpid).values())
    killed = []

    def kill_one_worker(row):
        if not killed:  # after the first result, while the others run
            os.kill(workers[0], signal.SIGKILL)
            killed.append(workers[0])

    rows = sweep.run_sweep(client, tasks, os.path.abspath(CLI), retries=2, on_result=kill_one_worker)
    assert killed
    assert [row["status"] for row in rows] == ["ok"] * 4, rows
    assert all(row["cpu_s"] > 0 and row["peak_rss_mb"] > 0 for row in rows)
    for task in tasks:
        assert os.path.isfile(os.path.join(task["out"], "map", "trajectory.txt"))

    seen = []
    again = sweep.run_sweep(client, tasks, os.path.abspath(CLI), on_result=seen.append)
    assert seen == [], "a rerun ran finished tasks again"
    key = lambda row: (row["log"], row["method"], row["config"], row["status"], row["out"])  # noqa: E731
    assert [key(row) for row in again] == [key(row) for row in rows]
    sweep.write_tables(rows, str(tmp_path))
    with open(tmp_path / "results.csv", encoding="utf-8") as f:
        assert len(f.read().strip().splitlines()) == 5


def test_a_failing_task_is_reported_and_the_others_finish(logs, client, tmp_path):
    tasks = sweep.make_tasks(logs[:1] + [str(tmp_path / "missing.clf")], ["graph"], {}, None, str(tmp_path))
    rows = sweep.run_sweep(client, tasks, os.path.abspath(CLI), retries=1)
    assert rows[0]["status"] == "ok"
    assert rows[1]["status"].startswith("failed") and "missing.clf" in rows[1]["status"]


def test_a_grid_names_configurations_and_relations_are_found(tmp_path):
    log = tmp_path / "intel.clf.gz"
    log.write_text("")
    (tmp_path / "intel.relations").write_text("")
    tasks = sweep.make_tasks([str(log)], ["graph"], {"graph": {"coarse": {"map_resolution": 0.1}, "fine": {}}}, None,
                             str(tmp_path / "out"))
    assert [t["config"] for t in tasks] == ["coarse", "fine"]
    assert tasks[0]["fields"] == {"map_resolution": 0.1}
    assert tasks[0]["relations"] == str(tmp_path / "intel.relations")
    assert tasks[0]["out"].endswith("intel__graph__coarse")
