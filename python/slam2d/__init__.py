# SPDX-License-Identifier: BSD-3-Clause
"""slam2d: 2D LiDAR scan matching, SLAM, localization and evaluation, from Python.

The C++ library through pybind11 (_slam2d), with numpy arrays in and out:

    import numpy as np, slam2d
    result = slam2d.match(target_points, source_points, slam2d.SE2(0.1, 0, 0), method="pl-icp")
    result.pose                # SE2: T_target_source
    run = slam2d.map_log("intel.clf.gz", method="graph", out="run")
    run.trajectory             # N x 4: t, x, y, theta, one row per scan (the CLI's trajectory)
    slam2d.relation_error(run.trajectory, "intel.relations")["trans_mean"]
"""

import json
import os
import tempfile
from dataclasses import dataclass

import numpy as np

import yaml

from ._slam2d import SE2, Cloud, Error, LogReader, MatchResult, Scan, matcher_names, method_names
from . import _slam2d

__all__ = ["SE2", "Cloud", "Scan", "Error", "MatchResult", "MapRun", "LogReader", "matcher_names", "method_names", "match",
           "map_log", "relation_error", "scan_points", "read_log", "default_config", "GraphSlam", "HectorSlam",
           "RbpfSlam", "Localizer"]


def default_config(name):
    """A method's or matcher's configuration with its defaults, as a dict (the C++ field table's
    fields and sections; `slam2d config dump NAME`). Change it and pass it back as `config`."""
    config = yaml.safe_load(_slam2d.default_preset(name))
    config.pop("method", None)
    config.pop("matcher", None)
    return config


def _preset_file(method, config, folder):
    """`config` (a dict of a method's fields) as a preset file the C++ side reads and checks."""
    path = os.path.join(folder, f"{method}.yaml")
    with open(path, "w", encoding="utf-8") as f:
        json.dump({"method": method, **config}, f)  # JSON is YAML
    return path


def _with_config(make, method, config, fields):
    config = {**(config or {}), **fields}
    if not config:
        return make("")
    with tempfile.TemporaryDirectory(prefix="slam2d-") as folder:
        return make(_preset_file(method, config, folder))


def GraphSlam(config=None, **fields):
    """Graph SLAM, one scan at a time: add_scan(scan, odom=None) -> SE2, finish(), .trajectory (N x 4),
    .map. `config` / keywords: fields of default_config("graph"); a bad one is an Error naming it."""
    return _with_config(_slam2d.GraphSlam, "graph", config, fields)


def HectorSlam(config=None, **fields):
    """Hector SLAM, one scan at a time (fields of default_config("hector"))."""
    return _with_config(_slam2d.HectorSlam, "hector", config, fields)


def RbpfSlam(config=None, **fields):
    """The Rao-Blackwellized particle filter, one scan at a time (fields of default_config("rbpf"));
    add_scan needs the odometry pose."""
    return _with_config(_slam2d.RbpfSlam, "rbpf", config, fields)


def Localizer(map, method="mcl", initial=None, sigma=(0.3, 0.3, 0.2), config=None, particles=None, seed=None, **fields):
    """Localization in a known map (a map YAML, e.g. from map_log) with `method` markov, ekf, mcl or
    hybrid, started at `initial` (an SE2, with standard deviations `sigma`) or globally (None; not
    the EKF). update(odom, scan) -> {"pose": SE2, "covariance": 3 x 3, "localized": bool};
    .trajectory. `config` / keywords: fields of default_config(method)."""
    def make(preset):
        return _slam2d.Localizer(os.fspath(map), method, initial, np.asarray(sigma, dtype=np.float64), preset, particles,
                                 seed)
    return _with_config(make, method, config, fields)


def read_log(path, scan_topic="", odom_topic="", fov_deg=None):
    """The messages of a log (CARMEN, ROS 1 bag, MCAP file, rosbag2 folder) in order, as dicts:
    {"kind": "scan", "scan": Scan (ranges as numpy), "odom": SE2 or None, "type": ...},
    {"kind": "odometry", "stamp", "pose", "tv", "rv"}, {"kind": "imu", ...}, {"kind": "true_pose", ...}."""
    return LogReader(os.fspath(path), scan_topic, odom_topic, fov_deg)


def _config_text(config):
    """A config given as keyword arguments, as the YAML (JSON is YAML) the C++ field tables read."""
    return json.dumps(config) if config else ""


def scan_points(ranges, angle_min, angle_increment, range_max=np.inf, range_min=0.0):
    """The end points (N x 2) of a scan's valid beams: finite ranges in [range_min, range_max)."""
    ranges = np.asarray(ranges, dtype=np.float64)
    angles = angle_min + angle_increment * np.arange(ranges.size)
    valid = np.isfinite(ranges) & (ranges >= range_min) & (ranges < range_max)
    return np.column_stack((ranges[valid] * np.cos(angles[valid]), ranges[valid] * np.sin(angles[valid])))


def match(target, source, guess=None, method="pl-icp", **config):
    """Matches `source` to `target` (N x 2 points, anything numpy makes one of, or a Cloud: made once,
    matched many times without copying its points again) from `guess`
    (an SE2, identity by default) with the scan matcher `method` (slam2d.matcher_names()); keyword
    arguments set fields of its configuration, as a preset file would (`slam2d config dump NAME`).
    Returns a MatchResult: .pose (SE2 T_target_source), .covariance (3 x 3), .degenerate,
    .weak_direction, .iterations, .inliers, .converged, .residual."""
    guess = guess if guess is not None else SE2()
    if isinstance(target, Cloud) and isinstance(source, Cloud):
        return _slam2d.match_clouds(target, source, guess, method, _config_text(config))
    return _slam2d.match(np.asarray(target, dtype=np.float64), np.asarray(source, dtype=np.float64), guess, method,
                         _config_text(config))


@dataclass
class MapRun:
    """A `slam2d map` run: the trajectory (N x 4: t, x, y, theta, one row per scan), the map
    (`cells` height x width int8, -1 unknown else occupancy 0..100, row 0 at the smallest y;
    `resolution` m per cell; `origin` the SE2 of cell (0, 0)'s lower-left corner), the summary
    (summary.json as a dict) and the folder holding map.pgm, map.yaml, trajectory.txt, ..."""
    trajectory: np.ndarray
    map: dict
    summary: dict
    out: str


def map_log(log, method="graph", out=None, config=None, seed=None, resolution=None, no_odometry=False,
            trajectory_frame="robot", odometry_source="log", scan_rate=None, odometry_smoothing=True):
    """Maps a log (CARMEN, ROS 1 bag, MCAP or rosbag2 folder) as `slam2d map` does, with the same
    code: the trajectory is the CLI's, bit for bit. `out` is the output folder (a temporary one,
    removed afterwards, when None); `config` a preset file (configs/<method>.yaml) or a dict of the
    method's fields (default_config(method)). `odometry_source` and `scan_rate` are the CLI's
    --odometry-source (log, none, hector or a trajectory file) and --scan-rate (Hz);
    `odometry_smoothing=False` is --no-odometry-smoothing (the method's own poses); method
    "hector+graph" or "hector+rbpf" runs the 2015 chain (docs/methods/fusion.md)."""
    def run(folder):
        with tempfile.TemporaryDirectory(prefix="slam2d-") as presets:
            preset = _preset_file(method, config, presets) if isinstance(config, dict) else os.fspath(config or "")
            result = _slam2d.map_log(os.fspath(log), method, folder, preset, seed, resolution, no_odometry,
                                     trajectory_frame, os.fspath(odometry_source), scan_rate, odometry_smoothing)
        return MapRun(result["trajectory"], result["map"], json.loads(result["summary"]), folder)
    if out is not None:
        return run(os.fspath(out))
    with tempfile.TemporaryDirectory(prefix="slam2d-") as folder:
        mapped = run(folder)
        mapped.out = None
        return mapped


def relation_error(trajectory, relations):
    """The relation error (Kuemmerle et al. 2009) of an N x 4 trajectory (t, x, y, theta) against a
    relations file: dict with relations, missing, trans_mean (m), trans_std (m), rot_mean_deg."""
    return _slam2d.relation_error(np.asarray(trajectory, dtype=np.float64), os.fspath(relations))
