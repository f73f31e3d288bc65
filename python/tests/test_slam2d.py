# SPDX-License-Identifier: BSD-3-Clause
"""The Python API against the C++ library's properties: SE2's group laws, every matcher recovering
a known motion, and map_log giving the command line's trajectory bit for bit."""

import json
import math
import os
import subprocess

import numpy as np
import pytest

import slam2d

DATA = os.environ.get("SLAM2D_DATA")
REQUIRE_DATA = os.environ.get("SLAM2D_REQUIRE_DATA") == "1"


def test_se2_group_laws():
    a = slam2d.SE2(1.0, -2.0, 0.7)
    b = slam2d.SE2(-0.3, 0.5, -2.1)
    np.testing.assert_allclose((a * b).matrix(), a.matrix() @ b.matrix(), atol=1e-12)
    np.testing.assert_allclose((a * a.inverse()).vector(), [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(slam2d.SE2.exp(a.log()).vector(), a.vector(), atol=1e-12)
    np.testing.assert_allclose(a * np.array([1.0, 0.0]), a.matrix()[:2, :2] @ [1, 0] + [1, -2], atol=1e-12)
    assert (a.x, a.y, a.theta) == (1.0, -2.0, 0.7)


def room(n=720):
    """The end points of a 360 deg scan in a 10 x 6 m room with a pillar, from (0.5, 0.3)."""
    angles = np.linspace(-math.pi, math.pi, n, endpoint=False)
    points = []
    for a in angles:
        d = np.array([math.cos(a), math.sin(a)])
        best = np.inf
        for axis, wall in ((0, 5.0), (0, -5.0), (1, 3.0), (1, -3.0)):
            if abs(d[axis]) > 1e-9:
                t = (wall - [0.5, 0.3][axis]) / d[axis]
                if t > 0:
                    best = min(best, t)
        # a pillar of radius 0.4 at (2, 1)
        o = np.array([0.5, 0.3]) - [2.0, 1.0]
        b = o @ d
        c = o @ o - 0.16
        if b * b - c > 0 and -b - math.sqrt(b * b - c) > 0:
            best = min(best, -b - math.sqrt(b * b - c))
        points.append(best * d)
    return np.array(points)


@pytest.mark.parametrize("method", slam2d.matcher_names())
def test_every_matcher_recovers_a_known_motion(method):
    target = room()
    truth = slam2d.SE2(0.12, -0.07, 0.04)
    inverse = truth.inverse()
    source = np.array([inverse * p for p in target])  # the scene seen from `truth`
    result = slam2d.match(target, source, slam2d.SE2(), method=method)
    assert abs(result.pose.x - truth.x) < 0.03, result.pose
    assert abs(result.pose.y - truth.y) < 0.03, result.pose
    assert abs(result.pose.theta - truth.theta) < 0.01, result.pose
    assert result.covariance.shape == (3, 3)


def test_clouds_made_once_match_as_the_arrays_do():
    target = room()
    source = np.array([slam2d.SE2(0.05, 0.02, 0.01).inverse() * p for p in target])
    cloud_target, cloud_source = slam2d.Cloud(target), slam2d.Cloud(source)
    assert len(cloud_target) == len(target)
    np.testing.assert_array_equal(cloud_target.points(), target)
    for method in ("icp", "pl-icp"):
        from_arrays = slam2d.match(target, source, method=method)
        from_clouds = slam2d.match(cloud_target, cloud_source, method=method)
        assert from_clouds.pose == from_arrays.pose


def test_a_config_reaches_the_matcher_and_a_bad_one_is_refused():
    target = room()
    few = slam2d.match(target, target, method="icp", max_iterations=1)
    assert few.iterations <= 1
    with pytest.raises(slam2d.Error, match="no_such_field"):
        slam2d.match(target, target, method="icp", no_such_field=3)
    with pytest.raises(ValueError):
        slam2d.match(np.zeros((4, 3)), target)


def test_scan_points_keeps_the_valid_beams():
    points = slam2d.scan_points([1.0, np.inf, np.nan, 2.0, 50.0], -0.2, 0.1, range_max=30.0)
    np.testing.assert_allclose(points, [[math.cos(-0.2), math.sin(-0.2)], [2 * math.cos(0.1), 2 * math.sin(0.1)]])


def test_map_log_is_the_command_lines_run_bit_for_bit(tmp_path):
    if not DATA:
        if REQUIRE_DATA:
            pytest.fail("SLAM2D_DATA is required")
        pytest.skip("SLAM2D_DATA is not set: the real-log test is skipped")
    log = os.path.join(DATA, "aces", "aces.clf.gz")
    run = slam2d.map_log(log, method="graph", out=tmp_path / "python")
    cli = os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d")
    subprocess.run([cli, "map", log, "--method", "graph", "--out", str(tmp_path / "cli"), "--quiet"], check=True,
                   capture_output=True)
    cli_rows = np.loadtxt(tmp_path / "cli" / "trajectory.txt", comments="#")
    assert run.trajectory.shape == (7374, 4)
    python_rows = np.loadtxt(tmp_path / "python" / "trajectory.txt", comments="#")
    assert np.array_equal(python_rows, cli_rows)
    assert run.summary["scans"] == 7374
    assert run.map["cells"].shape == (run.summary["map_height"], run.summary["map_width"])
    error = slam2d.relation_error(run.trajectory, os.path.join(DATA, "aces", "aces.relations"))
    assert error["relations"] == 1279 and error["trans_mean"] < 0.05
    cli_error = json.loads(subprocess.run([cli, "eval", str(tmp_path / "cli" / "trajectory.txt"), "--relations",
                                           os.path.join(DATA, "aces", "aces.relations"), "--json"],
                                          check=True, capture_output=True, text=True).stdout)
    assert error["trans_mean"] == pytest.approx(cli_error["trans_mean"], rel=1e-9)


def test_errors_name_the_file(tmp_path):
    with pytest.raises(slam2d.Error, match="nothing.clf"):
        slam2d.map_log(tmp_path / "nothing.clf")


def require_data():
    if not DATA:
        if REQUIRE_DATA:
            pytest.fail("SLAM2D_DATA is required")
        pytest.skip("SLAM2D_DATA is not set: the real-log test is skipped")


def test_graph_slam_one_scan_at_a_time_is_map_log():
    require_data()
    log = os.path.join(DATA, "aces", "aces.clf.gz")
    slam = slam2d.GraphSlam()
    scans = 0
    for message in slam2d.read_log(log):
        if message["kind"] == "scan":
            assert isinstance(message["scan"].ranges, np.ndarray) and message["scan"].ranges.size == 180
            slam.add_scan(message["scan"], message["odom"])
            scans += 1
    slam.finish()
    assert scans == 7374
    # The session gives the method's own poses; map_log smooths them with the odometry unless told not to.
    batch = slam2d.map_log(log, method="graph", odometry_smoothing=False)
    assert np.array_equal(slam.trajectory, batch.trajectory)
    assert np.array_equal(slam.map["cells"], batch.map["cells"])


def test_configs_are_dicts_of_the_field_tables(tmp_path):
    config = slam2d.default_config("graph")
    assert config["map_resolution"] == 0.05
    slam = slam2d.GraphSlam(config, map_resolution=0.1)
    ranges = np.full(360, 3.0)
    slam.add_scan(slam2d.Scan(ranges, -math.pi, 2 * math.pi / 360, 30.0), slam2d.SE2())
    slam.finish()
    assert slam.map["resolution"] == 0.1
    assert slam.trajectory.shape == (1, 4)
    with pytest.raises(slam2d.Error, match="map_resolutoin"):
        slam2d.GraphSlam(map_resolutoin=0.1)
    with pytest.raises(ValueError):
        slam2d.RbpfSlam().add_scan(slam2d.Scan(ranges, -math.pi, 0.01, 30.0))
    for name in slam2d.method_names() + slam2d.matcher_names():
        assert isinstance(slam2d.default_config(name), dict), name


def test_read_log_reads_bags_and_scans_give_points():
    require_data()
    messages = list(slam2d.read_log(os.path.join(DATA, "bags", "ros1", "aces_head_lz4.bag")))
    scans = [m for m in messages if m["kind"] == "scan"]
    assert len(scans) == 600
    assert sum(m["kind"] == "odometry" for m in messages) > 500
    points = scans[0]["scan"].points()
    assert points.ndim == 2 and points.shape[1] == 2 and 0 < len(points) <= 180


def test_localizer_is_the_command_lines_localize(tmp_path):
    cli = os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d")
    log, truth = str(tmp_path / "office.clf"), str(tmp_path / "truth.txt")
    subprocess.run([cli, "simulate", "--quiet", "--duration", "60", "--seed", "3", "--out", log, "--truth", truth], check=True)
    slam2d.map_log(log, method="odometry", out=tmp_path / "map")
    x, y, theta = np.loadtxt(truth, comments="#")[0][1:4]
    for method in ("mcl", "ekf"):
        localizer = slam2d.Localizer(tmp_path / "map" / "map.yaml", method=method, initial=slam2d.SE2(x, y, theta), seed=2)
        last = None
        for message in slam2d.read_log(log):
            if message["kind"] == "scan":
                last = localizer.update(message["odom"], message["scan"])
        assert last["localized"], method
        out = tmp_path / f"{method}.txt"
        subprocess.run([cli, "localize", log, "--map", str(tmp_path / "map" / "map.yaml"), "--method", method,
                        f"--initial={x!r},{y!r},{theta!r}", "--seed", "2", "--out", str(out), "--quiet",
                        "--no-odometry-smoothing"],  # the online estimates, as the Localizer gives them
                       check=True, capture_output=True)
        cli_rows = np.loadtxt(out, comments="#")
        assert localizer.trajectory.shape == cli_rows.shape, method
        np.testing.assert_allclose(localizer.trajectory, cli_rows, rtol=0, atol=1e-9, err_msg=method)
    with pytest.raises(slam2d.Error, match="EKF has no global mode"):
        slam2d.Localizer(tmp_path / "map" / "map.yaml", method="ekf")


def test_map_log_runs_the_2015_chain_and_takes_a_trajectory_as_odometry(tmp_path):
    cli = os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d")
    log, truth = str(tmp_path / "office.clf"), str(tmp_path / "truth.txt")
    subprocess.run([cli, "simulate", "--quiet", "--duration", "60", "--seed", "3", "--out", log, "--truth", truth], check=True)
    truth_rows = np.loadtxt(truth, comments="#")
    chain = slam2d.map_log(log, method="hector+graph", out=tmp_path / "chain")
    assert chain.trajectory.shape == truth_rows.shape  # dense: one pose per scan
    assert chain.summary["odometry_source"] == "hector"
    sparse = np.loadtxt(tmp_path / "chain" / "sparse_trajectory.txt", comments="#")
    assert abs(len(sparse) - 3 * (truth_rows[-1, 0] - truth_rows[0, 0])) <= 3  # 3 scans a second
    x0, y0, theta0 = truth_rows[0, 1:4]  # without wheel odometry the map frame is the first pose's
    c, s = math.cos(theta0), math.sin(theta0)
    placed = chain.trajectory[:, 1:3] @ np.array([[c, s], [-s, c]]) + [x0, y0]
    assert np.max(np.hypot(*(placed - truth_rows[:, 1:3]).T)) < 0.5  # unaligned: the first heading error swings it
    replayed = slam2d.map_log(log, method="odometry", odometry_source=truth, scan_rate=5.0)
    assert abs(len(replayed.trajectory) - 5 * (truth_rows[-1, 0] - truth_rows[0, 0])) <= 5
    at = np.searchsorted(truth_rows[:, 0], replayed.trajectory[:, 0])
    np.testing.assert_allclose(replayed.trajectory[:, 1:3], truth_rows[at, 1:3], atol=1e-9)
