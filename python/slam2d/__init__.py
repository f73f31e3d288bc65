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

from ._slam2d import SE2, Error, MatchResult, matcher_names
from . import _slam2d

__all__ = ["SE2", "Error", "MatchResult", "MapRun", "matcher_names", "match", "map_log", "relation_error", "scan_points"]


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
    """Matches `source` to `target` (N x 2 points, or anything numpy makes one of) from `guess`
    (an SE2, identity by default) with the scan matcher `method` (slam2d.matcher_names()); keyword
    arguments set fields of its configuration, as a preset file would (`slam2d config dump NAME`).
    Returns a MatchResult: .pose (SE2 T_target_source), .covariance (3 x 3), .degenerate,
    .weak_direction, .iterations, .inliers, .converged, .residual."""
    return _slam2d.match(np.asarray(target, dtype=np.float64), np.asarray(source, dtype=np.float64),
                         guess if guess is not None else SE2(), method, _config_text(config))


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
            trajectory_frame="robot"):
    """Maps a log (CARMEN, ROS 1 bag, MCAP or rosbag2 folder) as `slam2d map` does, with the same
    code: the trajectory is the CLI's, bit for bit. `out` is the output folder (a temporary one,
    removed afterwards, when None); `config` a preset file (configs/<method>.yaml)."""
    def run(folder):
        result = _slam2d.map_log(os.fspath(log), method, folder, config or "", seed, resolution, no_odometry,
                                 trajectory_frame)
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
