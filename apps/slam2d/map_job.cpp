// SPDX-License-Identifier: BSD-3-Clause
#include "map_job.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <filesystem>

#include "odometry_report.hpp"
#include "progress.hpp"
#include "run_mcap_output.hpp"
#include "run_stats.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/grid/render.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/methods/method_presets.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"

namespace slam2d::cli {

namespace {

struct MappingRun {
  OccupancyMap map;
  Trajectory trajectory;
  std::optional<PoseGraph> graph;  // graph SLAM's optimised pose graph
  JsonObject method_summary;       // what the method adds to summary.json
  std::size_t backwards_timestamps = 0;
  std::size_t skipped_lines = 0;
  std::size_t odometry_steps_reversed = 0;  // repaired by the reader (reversing integrated as forward)
  double data_duration = 0.0;  // s, last scan stamp minus first, in file order
  std::vector<std::string> warnings;  // what the reader and the method could not decide
  double resolution = 0.0;            // m per cell of the map written
  SE2 T_robot_sensor;                 // the first scan's mounting (--trajectory-frame sensor)
};


// The odometry guard's counts and its warning, into the run.
void report_odometry(MappingRun& run, const OdometryGuardStats& stats) {
  run.method_summary.merge(odometry_report(stats));
  if (const auto warning = odometry_warning(stats)) run.warnings.push_back(*warning);
}

// Streams the log's laser scans to `add_scan(laser)` (which returns the robot pose it estimated),
// with the progress line; fills every field of the run but the map.
template <typename AddScan>
MappingRun run_over_scans(const MapJobOptions& options, AddScan&& add_scan) {
  LogReader reader(options.log, options.input);
  Progress progress("map", options.quiet);
  MappingRun run;
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr) continue;
    if (!laser->has_poses && !options.no_odometry) {
      throw ParseError(reader.path(), laser->line,
                       laser->type + " carries no odometry pose; use FLASER, RLASER or ROBOTLASER1 logs, a bag with "
                       "odometry, or --no-odometry");
    }
    if (run.trajectory.empty()) run.T_robot_sensor = laser->scan.T_robot_sensor;
    run.trajectory.push_back(laser->scan.stamp, add_scan(*laser));
    if (run.trajectory.size() % 256 == 0) {
      progress.update(reader.progress(), fmt::format("{} scans", run.trajectory.size()));
    }
  }
  progress.finish();
  print_reader_warnings(reader);
  run.warnings = reader_warnings(reader);
  check(!run.trajectory.empty(), reader.path() + ": no laser scans in the log");
  run.backwards_timestamps = reader.stats().backwards_laser_timestamps;
  run.skipped_lines = reader.stats().skipped_lines;
  run.odometry_steps_reversed = reader.stats().odometry_steps_reversed;
  run.data_duration = run.trajectory.back().stamp - run.trajectory.front().stamp;
  return run;
}

// Odometry mapping: every scan is placed at the robot's odometry pose at its stamp.
MappingRun map_with_odometry(const MapJobOptions& options) {
  check(!options.no_odometry, "map: the odometry method needs odometry (drop --no-odometry)");
  check(options.config.empty(), "map: the odometry method has no settings for --config");
  OccupancyGrid grid(OccupancyGridConfig{.resolution = options.resolution.value_or(0.05)});
  MappingRun run = run_over_scans(options, [&](const LaserMessage& laser) {
    grid.integrate_scan(laser.scan, laser.odom_pose);
    return laser.odom_pose;
  });
  run.map = grid.to_occupancy_map();
  run.resolution = grid.geometry().resolution;
  return run;
}

// Hector SLAM (Kohlbrecher et al. 2011): scan-to-map matching on a map pyramid, odometry as the
// initial guess unless --no-odometry. The map written is the finest pyramid level.
MappingRun map_with_hector(const MapJobOptions& options) {
  HectorSlamConfig config = read_method_preset(options.config, options.method, HectorSlamConfig{});
  if (options.levels) config.map.levels = *options.levels;
  if (options.resolution) config.map.grid.resolution = *options.resolution;
  if (options.no_odometry) config.prior = MotionPrior::kLastPose;
  HectorSlam slam(config);
  MappingRun run = run_over_scans(options, [&](const LaserMessage& laser) {
    HectorInputs inputs;
    if (!options.no_odometry) inputs.T_odom_robot = laser.odom_pose;
    return slam.add_scan(laser.scan, inputs).T_map_robot;
  });
  run.map = slam.map().level(0).to_occupancy_map();
  run.resolution = config.map.grid.resolution;
  run.method_summary.add("odometry", !options.no_odometry).add("levels", config.map.levels);
  if (!options.no_odometry) report_odometry(run, slam.odometry_stats());
  return run;
}

// Graph SLAM (slam/graph): keyframes, scan-to-local-map constraints, loop closure, sparse pose
// adjustment. The trajectory's scans between keyframes follow the odometry between them.
MappingRun map_with_graph(const MapJobOptions& options) {
  GraphSlamConfig config = read_method_preset(options.config, options.method, GraphSlamConfig{});
  if (options.resolution) config.map_resolution = *options.resolution;
  GraphSlam slam(config);
  MappingRun run = run_over_scans(options, [&](const LaserMessage& laser) {
    const std::optional<SE2> odometry = options.no_odometry ? std::nullopt : std::optional<SE2>(laser.odom_pose);
    return slam.add_scan(laser.scan, odometry).T_map_robot;
  });
  slam.finish();
  run.trajectory = slam.trajectory();
  run.map = slam.map();
  run.graph = slam.graph();
  run.resolution = config.map_resolution;
  const GraphSlamStats& stats = slam.stats();
  run.method_summary.add("odometry", !options.no_odometry).add("keyframes", stats.keyframes);
  run.method_summary.add("loop_closures", stats.loop_closures).add("near_links", stats.near_links);
  run.method_summary.add("loop_attempts", stats.loop_attempts);
  run.method_summary.add("global_searches", stats.global_searches).add("global_closures", stats.global_closures);
  run.method_summary.add("large_closures", stats.large_closures).add("unconfirmed_closures", stats.unconfirmed_closures);
  run.method_summary.add("final_search_closures", stats.final_search_closures);
  run.method_summary.add("global_search_s", stats.global_search_seconds);
  if (stats.unconfirmed_closures > 0) {  // graph SLAM could not decide: say so instead of bending the map
    run.warnings.push_back(fmt::format("graph: {} large loop corrections found but not confirmed by a second keyframe "
                                       "were left out; a loop may be left open",
                                       stats.unconfirmed_closures));
  }
  run.method_summary.add("optimizations", stats.optimizations).add("sequential_failures", stats.sequential_failures);
  run.method_summary.add("optimization_s", stats.optimization_seconds).add("final_chi2", chi2(slam.graph()));
  if (!options.no_odometry) report_odometry(run, slam.odometry_stats());
  return run;
}

// Rao-Blackwellized particle filter (slam/rbpf, GMapping-class): the trajectory is the best
// particle's path, one pose per scan (scans between updates follow the scan-matched odometry).
MappingRun map_with_rbpf(const MapJobOptions& options) {
  check(!options.no_odometry, "map: the rbpf method needs odometry (drop --no-odometry)");
  RbpfConfig config = read_method_preset(options.config, options.method, RbpfConfig{});
  if (options.particles) config.particles = *options.particles;
  if (options.seed) config.seed = *options.seed;
  if (options.threads) config.threads = *options.threads;
  if (options.resolution) config.map.grid.resolution = *options.resolution;
  RbpfSlam slam(config);
  MappingRun run = run_over_scans(options, [&](const LaserMessage& laser) {
    return slam.add_scan(laser.scan, laser.odom_pose).T_map_robot;
  });
  run.trajectory = slam.trajectory();
  run.map = slam.map().to_occupancy_map();
  run.resolution = config.map.grid.resolution;
  const RbpfStats& stats = slam.stats();
  run.method_summary.add("particles", config.particles).add("seed", static_cast<std::size_t>(config.seed));
  run.method_summary.add("threads", config.threads);
  run.method_summary.add("updates", stats.updates).add("resamplings", stats.resamplings);
  run.method_summary.add("neff_min", stats.neff_min).add("fallbacks", stats.fallbacks);
  report_odometry(run, slam.odometry_stats());
  return run;
}

std::vector<SE2> poses_of(const Trajectory& trajectory) {
  std::vector<SE2> poses;
  poses.reserve(trajectory.size());
  for (const auto& stamped : trajectory) poses.push_back(stamped.pose);
  return poses;
}

void write_outputs(const std::filesystem::path& dir, const MappingRun& run, const JsonObject& summary,
                   TrajectoryFormat format) {
  std::filesystem::create_directories(dir);
  write_map((dir / "map.yaml").string(), run.map, "map.pgm");
  write_png((dir / "map.png").string(), render_map(run.map, poses_of(run.trajectory)));
  write_trajectory((dir / "trajectory.txt").string(), run.trajectory, format);
  if (run.graph) write_g2o((dir / "graph.g2o").string(), to_pose_graph_file(*run.graph));
  write_file_atomically((dir / "summary.json").string(), summary.dump());
}

MappingRun run_method(const MapJobOptions& options) {
  if (options.method == "hector") return map_with_hector(options);
  if (options.method == "graph") return map_with_graph(options);
  if (options.method == "rbpf") return map_with_rbpf(options);
  return map_with_odometry(options);
}

}  // namespace

const std::vector<std::string>& map_methods() {
  static const std::vector<std::string> methods{"odometry", "hector", "graph", "rbpf"};
  return methods;
}

MapJobResult run_map_job(const MapJobOptions& options) {
  const auto& methods = map_methods();
  check(std::find(methods.begin(), methods.end(), options.method) != methods.end(),
        "map: unknown method '" + options.method + "' (known: odometry, hector, graph, rbpf)");
  check(!options.particles || (*options.particles >= 1 && *options.particles <= 10000), "map: --particles must be in [1, 10000]");
  check(!options.resolution || (*options.resolution > 0.0 && *options.resolution <= 10.0), "map: --resolution must be in (0, 10] m");
  check(!options.levels || (*options.levels >= 1 && *options.levels <= 16), "map: --levels must be in [1, 16]");
  trajectory_format_from_name(options.trajectory_format);  // checked before the work
  check(options.trajectory_frame == "robot" || options.trajectory_frame == "sensor",
        "map: --trajectory-frame must be robot or sensor");
  const RunClock clock;
  MappingRun run = run_method(options);
  const double cpu = clock.cpu_seconds();
  const double wall = clock.wall_seconds();

  JsonObject summary;
  summary.add("method", options.method).add("log", options.log).add("scans", run.trajectory.size());
  summary.add("data_duration_s", run.data_duration).add("cpu_s", cpu).add("wall_s", wall);
  summary.add("realtime_factor", cpu > 0.0 ? std::optional<double>(run.data_duration / cpu) : std::nullopt);
  summary.add("us_per_scan", 1e6 * cpu / static_cast<double>(run.trajectory.size()));
  if (!options.config.empty()) summary.add("config", options.config);
  summary.merge(run.method_summary);
  summary.add("resolution", run.resolution).add("map_width", run.map.width).add("map_height", run.map.height);
  summary.add("backwards_timestamps", run.backwards_timestamps).add("skipped_lines", run.skipped_lines);
  summary.add("odometry_steps_reversed", run.odometry_steps_reversed);
  summary.add("peak_rss_mb", peak_rss_mb());
  summary.add("warnings", run.warnings);
  if (!options.mcap.empty()) write_run_mcap(options.mcap, options.log, options.input, false, run.map, run.trajectory);
  if (options.trajectory_frame == "sensor") {  // the laser's pose: what a benchmark's relations may describe
    Trajectory sensor;
    sensor.reserve(run.trajectory.size());
    for (const StampedPose& stamped : run.trajectory) sensor.push_back(stamped.stamp, stamped.pose * run.T_robot_sensor);
    run.trajectory = std::move(sensor);
  }
  write_outputs(options.out_dir, run, summary, trajectory_format_from_name(options.trajectory_format));
  return {std::move(run.map), std::move(run.trajectory), std::move(summary)};
}

}  // namespace slam2d::cli
