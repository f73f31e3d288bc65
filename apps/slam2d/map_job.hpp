// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The mapping job behind `slam2d map` (and `slam2d demo`): read a log, estimate the trajectory
// with the chosen method, build the occupancy grid, write the outputs.

#include <cstdint>
#include <optional>
#include <string>

#include "json.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/io/log_reader.hpp"

namespace slam2d::cli {

struct MapJobOptions {
  std::string log;                  // CARMEN log (plain or .gz), ROS 1 bag, MCAP file or rosbag2 folder
  std::string out_dir;              // written: map.pgm, map.yaml, map.png, trajectory.txt, summary.json
  std::string method = "odometry";  // odometry, hector, graph, rbpf, hector+graph, hector+rbpf (the 2015 chain)
  std::string trajectory_format = "text";  // trajectory.txt as slam2d text or TUM (evo)
  std::string trajectory_frame = "robot";  // robot (base) | sensor: the laser's pose, T_robot_sensor of the first scan applied
  std::string mcap;                 // when set: the run for Foxglove (io/run_mcap.hpp) written there too
  std::string reference;            // when set: a trajectory drawn in map.png, aligned onto the run's as the ATE aligns it
  std::string config;               // hector, graph, rbpf: a method preset (configs/<method>.yaml); empty: the defaults
  // The odometry pose each scan carries into the method: "log" (the log's), "none" (hector: the
  // last pose; graph: constant velocity; rbpf: as "hector"), "hector" (Hector SLAM's
  // trajectory on the laser alone, its jumps smoothed), or a trajectory file's path.
  std::string odometry_source = "log";
  bool no_odometry = false;          // the same as odometry_source "none"
  // How far the log's odometry runs ahead of the laser: "auto" (estimated, compensated when
  // confident and significant), "off", or seconds (sensor_options.hpp). Only for odometry_source "log".
  std::string odometry_time_offset = "auto";
  // hector, graph, rbpf given odometry (log or a trajectory file): the per-scan poses smoothed
  // with the odometry's increments, each weighed by its own noise (slam/fusion/odometry_smoothing.hpp).
  bool odometry_smoothing = true;
  // The smoothing's noises estimated with PL-ICP scan odometry as a third stream, which tells the
  // method's slow error from the odometry's drift (odometry_smoothing.hpp, header 3). Off by
  // default: about 1 s of CPU on Intel, FR079 a little worse, one seed (docs/fusion_by_uncertainty.md).
  bool smoothing_third_stream = false;
  std::optional<double> scan_rate;   // Hz: the method sees at most one scan per 1/rate s (the time-based subset)
  // Overrides of the method's config (preset or defaults) when set:
  std::optional<double> resolution;      // m per cell (odometry: 0.05 when unset)
  std::optional<int> levels;             // hector: map pyramid levels, in [1, 16]
  std::optional<int> particles;          // rbpf: number of particles, in [1, 10000]
  std::optional<std::uint64_t> seed;     // rbpf: seed of every random draw (same log + seed, same result)
  std::optional<int> threads;            // rbpf: threads for the particles, in [0, 256] (0: all hardware threads); same result
  bool quiet = false;               // no progress line
  LogReaderOptions input;           // CARMEN geometry overrides, bag topics and frames (sensor_options.hpp)
};

struct MapJobResult {
  OccupancyMap map;
  Trajectory trajectory;  // one pose per scan used, in log order
  JsonObject summary;     // what summary.json holds
};

/// Runs the job and writes its outputs; nothing is written if the log cannot be read to the end.
MapJobResult run_map_job(const MapJobOptions& options);

/// The methods `--method` accepts.
const std::vector<std::string>& map_methods();

}  // namespace slam2d::cli
