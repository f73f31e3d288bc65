// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Real scans for the micro benchmarks: the first scans of $SLAM2D_DATA/<log>/<log>.clf.gz
// (default ../shared/data), read once. Empty when the data is absent; benchmarks then skip.

#include <benchmark/benchmark.h>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d::bench {

struct LoggedScan {
  LaserScan scan;
  SE2 odom_pose;   // T_odom_robot at the scan
  SE2 laser_pose;  // the log's own pose of the scan
};

/// Up to `count` front-laser scans of the log, in file order (cached per log name).
const std::vector<LoggedScan>& logged_scans(const std::string& log = "intel", std::size_t count = 2000);

/// The valid end points of scan i in its sensor frame, in beam order.
PointCloud2 sensor_cloud(const LaserScan& scan);

/// Consecutive scans of a log as sensor-frame clouds, with the odometry guess of each pair in
/// the sensor frames: guesses[i] = (odom_i T_robot_sensor)^-1 (odom_{i+1} T_robot_sensor).
struct ConsecutivePairs {
  std::vector<PointCloud2> clouds;
  std::vector<SE2> guesses;  // guesses[i]: T_sensor_i_sensor_{i+1}
};

/// The pairs of the first `count` scans of the log (cached per log name).
const ConsecutivePairs& consecutive_pairs(const std::string& log = "intel", std::size_t count = 1001);

/// Runs `match` on pair after pair (target i, source i + 1) of the log while the state runs, one
/// match per benchmark iteration; counters us_per_match, iterations and converged (means).
/// Skips with an error when the log is absent.
void run_consecutive_matches(benchmark::State& state, const Matcher& match, const std::string& log = "intel");

}  // namespace slam2d::bench
