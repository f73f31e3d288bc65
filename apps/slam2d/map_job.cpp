// SPDX-License-Identifier: BSD-3-Clause
#include "map_job.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "odometry_report.hpp"
#include "progress.hpp"
#include "run_mcap_output.hpp"
#include "run_stats.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/eval/ate.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/grid/render.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/methods/method_presets.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "slam2d/registration/scan_odometry.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/slam/fusion/discontinuity_smoothing.hpp"
#include "slam2d/slam/fusion/odometry_smoothing.hpp"
#include "slam2d/slam/fusion/trajectory_fusion.hpp"
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
  // A chain's parts (hector+graph, hector+rbpf): Hector's smoothed dense trajectory and the
  // sparse method's, written beside the fused one.
  std::optional<Trajectory> dense_trajectory;
  std::optional<Trajectory> sparse_trajectory;
  std::vector<SE2> odometry;  // the odometry pose each scan of the trajectory came with, when it came with one
  std::vector<SE2> scan_odometry;  // PL-ICP scan odometry at each scan: the smoothing's third stream
};

// Kaijaluoto et al. 2015's rate of the time-based subset the sparse method of a chain sees.
constexpr double kChainScanRate = 3.0;


// The odometry guard's counts and its warning, into the run.
void report_odometry(MappingRun& run, const OdometryGuardStats& stats) {
  run.method_summary.merge(odometry_report(stats));
  for (std::string& warning : odometry_warnings(stats)) run.warnings.push_back(std::move(warning));
}

// Gaps in the scans and the searches after them (Hector, the RBPF), into the run.
void report_gaps(MappingRun& run, const GapStats& gaps) {
  run.method_summary.add("scan_gaps", gaps.gaps).add("gaps_tracked_through", gaps.tracked).add("gap_relocalizations", gaps.relocalized);
  run.method_summary.add("gap_relocalization_attempts", gaps.attempts).add("gaps_not_relocalized", gaps.abandoned);
}

// Where each scan's odometry pose comes from (MapJobOptions::odometry_source, resolved).
struct OdometryFeed {
  enum class Kind { kLog, kNone, kTrajectory, kPerScan };
  Kind kind = Kind::kLog;
  // kTrajectory: sorted by stamp, interpolated at each scan's stamp; kPerScan: one pose per scan
  // of the same log read the same way, taken by the scan's index (a clock that steps back, as
  // Intel's does, cannot mislead it).
  Trajectory trajectory;
  std::string name;       // what the messages call it
  bool uses_odometry() const { return kind != Kind::kNone; }
  // A sensor of its own (the log's odometry, a trajectory file's), not poses the laser gave (Hector's).
  bool is_own_sensor() const { return kind == Kind::kLog || kind == Kind::kTrajectory; }

  static OdometryFeed none() { return {Kind::kNone, {}, "none"}; }
  static OdometryFeed from(Trajectory trajectory, std::string name) {
    return {Kind::kTrajectory, std::move(trajectory), std::move(name)};
  }
  static OdometryFeed per_scan(Trajectory trajectory, std::string name) {
    return {Kind::kPerScan, std::move(trajectory), std::move(name)};
  }
};

// The time-based subset of the 2015 pipeline: one scan per slot of 1/rate s from the first scan,
// so the method sees the rate on average whatever the scanner's, and a standing robot still
// contributes scans.
class ScanRateFilter {
 public:
  explicit ScanRateFilter(std::optional<double> rate) : rate_(rate.value_or(0.0)) {}
  bool take(double stamp) {
    if (rate_ <= 0.0) return true;
    if (!started_) first_ = stamp;
    const double slot = std::floor((stamp - first_) * rate_);
    if (started_ && slot <= last_slot_) return false;
    started_ = true;
    last_slot_ = slot;
    return true;
  }

 private:
  double rate_ = 0.0;  // Hz; 0: every scan
  bool started_ = false;
  double first_ = 0.0;      // s, the first scan's stamp
  double last_slot_ = 0.0;  // the slot of the last scan taken
};

struct IgnoreImu {
  void operator()(const ImuMessage&) const {}
};

// Whether the method's poses are smoothed with the odometry (slam/fusion/odometry_smoothing.hpp):
// only with an odometry that is a sensor of its own (the log's, a trajectory file's); Hector's,
// the laser's, would share the method's errors.
bool smoothed_with_odometry(const MapJobOptions& options, const OdometryFeed& feed) {
  return options.odometry_smoothing && options.method != "odometry" && feed.is_own_sensor();
}

// The smoothing's third stream: PL-ICP scan odometry against the last keyframe alone (its
// projective search; the stream is there for its errors' independence, not its accuracy), from
// the odometry's guess. Neither guess makes it independent: from the odometry's it keeps part of
// the odometry's error (docs/methods/pl_icp.md), which makes the odometry look better than it is;
// from constant velocity it shares the method's errors under a noisy laser, which makes the
// method look better (docs/fusion_by_uncertainty.md). Only the first does no harm at 10 s.
ScanOdometry third_stream_odometry() {
  return ScanOdometry([](const PointCloud2& target, const PointCloud2& source,
                         const SE2& guess) { return match_pl_icp(target, source, guess); },
                      ScanOdometryConfig{.local_map_keyframes = 1});
}

// Streams the log's laser scans to `add_scan(laser, odometry)` (which returns the robot pose it
// estimated) and its IMU readings to `on_imu`, with the progress line; the scans left out by
// --scan-rate or outside a trajectory feed's span are skipped. Fills every field of the run but
// the map.
template <typename AddScan, typename OnImu = IgnoreImu>
MappingRun run_over_scans(const MapJobOptions& options, const OdometryFeed& feed, const std::string& label,
                          AddScan&& add_scan, OnImu&& on_imu = OnImu{}) {
  LogReader reader(options.log, options.input);
  Progress progress(label, options.quiet);
  MappingRun run;
  ScanRateFilter rate(options.scan_rate);
  std::optional<ScanOdometry> scan_odometry;
  if (options.smoothing_third_stream && smoothed_with_odometry(options, feed)) scan_odometry.emplace(third_stream_odometry());
  std::size_t outside_feed = 0;
  std::size_t scans = 0;
  while (auto message = reader.next()) {
    if (const auto* imu = std::get_if<ImuMessage>(&*message)) on_imu(*imu);
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr) continue;
    if (++scans % 256 == 0) progress.update(reader.progress(), fmt::format("{} scans", scans));
    if (feed.kind == OdometryFeed::Kind::kLog && !laser->has_poses) {
      throw ParseError(reader.path(), laser->line,
                       laser->type + " carries no odometry pose; use FLASER, RLASER or ROBOTLASER1 logs, a bag with "
                       "odometry, or --odometry-source none|hector|TRAJ");
    }
    if (!rate.take(laser->scan.stamp)) continue;
    std::optional<SE2> odometry;
    if (feed.kind == OdometryFeed::Kind::kLog) odometry = laser->odom_pose;
    if (feed.kind == OdometryFeed::Kind::kPerScan) {
      check(scans <= feed.trajectory.size(), reader.path() + ": more scans than the " + feed.name + " pass read");
      odometry = feed.trajectory[scans - 1].pose;
    }
    if (feed.kind == OdometryFeed::Kind::kTrajectory) {
      odometry = feed.trajectory.interpolate(laser->scan.stamp);
      if (!odometry) {
        ++outside_feed;
        continue;
      }
    }
    if (run.trajectory.empty()) run.T_robot_sensor = laser->scan.T_robot_sensor;
    run.trajectory.push_back(laser->scan.stamp, add_scan(*laser, odometry));
    if (odometry) run.odometry.push_back(*odometry);
    if (scan_odometry) run.scan_odometry.push_back(scan_odometry->add(laser->scan, odometry));
  }
  progress.finish();
  print_reader_warnings(reader);
  run.warnings = reader_warnings(reader);
  check(!run.trajectory.empty(), reader.path() + ": no laser scans in the log" +
                                     (outside_feed > 0 ? " within the odometry trajectory's span (" + feed.name + ")" : ""));
  if (outside_feed > 0) {
    run.warnings.push_back(fmt::format("{} scans outside the time span of the odometry trajectory {} were left out",
                                       outside_feed, feed.name));
  }
  run.method_summary.add("scans_read", scans);
  if (options.scan_rate) run.method_summary.add("scan_rate_hz", *options.scan_rate);
  if (feed.kind == OdometryFeed::Kind::kTrajectory) run.method_summary.add("scans_outside_odometry", outside_feed);
  run.backwards_timestamps = reader.stats().backwards_laser_timestamps;
  run.skipped_lines = reader.stats().skipped_lines;
  run.odometry_steps_reversed = reader.stats().odometry_steps_reversed;
  run.data_duration = run.trajectory.back().stamp - run.trajectory.front().stamp;
  return run;
}

// Odometry mapping: every scan is placed at the robot's odometry pose at its stamp (the log's, or
// a trajectory's: a map drawn from another run's poses).
MappingRun map_with_odometry(const MapJobOptions& options, const OdometryFeed& feed) {
  check(feed.uses_odometry(), "map: the odometry method needs odometry (--odometry-source log, hector or TRAJ)");
  check(options.config.empty(), "map: the odometry method has no settings for --config");
  OccupancyGrid grid(OccupancyGridConfig{.resolution = options.resolution.value_or(0.05)});
  MappingRun run = run_over_scans(options, feed, "map", [&](const LaserMessage& laser, const std::optional<SE2>& odometry) {
    grid.integrate_scan(laser.scan, *odometry);
    return *odometry;
  });
  run.map = grid.to_occupancy_map();
  run.resolution = grid.geometry().resolution;
  return run;
}

// Hector SLAM (Kohlbrecher et al. 2011): scan-to-map matching on a map pyramid, odometry as the
// initial guess when there is one, and the log's IMU (roll and pitch level the scan, the yaw rate
// corrects the sweep's motion distortion when the preset sets sweep_duration). The map written is
// the finest pyramid level.
MappingRun map_with_hector(const MapJobOptions& options, const OdometryFeed& feed) {
  HectorSlamConfig config = read_method_preset(options.config, "hector", HectorSlamConfig{});
  if (options.levels) config.map.levels = *options.levels;
  if (options.resolution) config.map.grid.resolution = *options.resolution;
  if (!feed.uses_odometry()) config.prior = MotionPrior::kLastPose;
  HectorSlam slam(config);
  std::optional<ImuReading> imu;  // the latest reading before the scan
  std::size_t imu_scans = 0;
  MappingRun run = run_over_scans(options, feed, "hector", [&](const LaserMessage& laser, const std::optional<SE2>& odometry) {
    HectorInputs inputs;
    inputs.T_odom_robot = odometry;
    if (imu && std::abs(laser.scan.stamp - imu->stamp) <= config.max_prior_dt) {
      inputs.attitude = Attitude{.roll = imu->roll, .pitch = imu->pitch};
      inputs.angular_rate = imu->yaw_rate;
      ++imu_scans;
    }
    return slam.add_scan(laser.scan, inputs).T_map_robot;
  }, [&](const ImuMessage& message) { imu = message.reading; });
  run.trajectory = slam.trajectory();  // the poses since a gap move when Hector finds its place again
  run.map = slam.occupancy_map();
  run.resolution = config.map.grid.resolution;
  run.method_summary.add("odometry", feed.uses_odometry()).add("levels", config.map.levels).add("imu_scans", imu_scans);
  run.method_summary.add("stuck_matches", slam.stuck_matches());
  report_gaps(run, slam.gap_stats());
  if (feed.uses_odometry()) {
    report_odometry(run, slam.odometry_stats());
    if (config.fuse_odometry) {
      run.method_summary.merge(fusion_report(slam.fusion_stats(), slam.odometry_noise()));
    } else if (config.prior_from_motion_noise) {
      run.method_summary.merge(odometry_noise_report(slam.odometry_noise()));
    }
    if (slam.calibrating()) run.method_summary.merge(calibration_report(slam.odometry_calibration()));
  }
  return run;
}
// Graph SLAM (slam/graph): keyframes, scan-to-local-map constraints, loop closure, sparse pose
// adjustment. The trajectory's scans between keyframes follow the odometry between them.
MappingRun map_with_graph(const MapJobOptions& options, const OdometryFeed& feed) {
  GraphSlamConfig config = read_method_preset(options.config, "graph", GraphSlamConfig{});
  // As the RBPF's below: Hector's poses (hector+graph, --odometry-source hector) come from the same
  // scans as the tracker's matches, so how well the two agree says nothing of their noise (ACES's
  // hector+graph: 0.110 m over all relations with the learnt prior, 0.057 m with the fixed one);
  // nor has it a systematic error of its own for the calibration to learn.
  if (!feed.is_own_sensor()) {
    config.tracking.prior_from_motion_noise = false;
    config.tracking.odometry_calibration.window = 0.0;
  }
  if (options.resolution) config.map_resolution = *options.resolution;
  GraphSlam slam(config);
  MappingRun run = run_over_scans(options, feed, "graph", [&](const LaserMessage& laser, const std::optional<SE2>& odometry) {
    return slam.add_scan(laser.scan, odometry).T_map_robot;
  });
  slam.finish();
  run.trajectory = slam.trajectory();
  run.map = slam.map();
  run.graph = slam.graph();
  run.resolution = config.map_resolution;
  const GraphSlamStats& stats = slam.stats();
  run.method_summary.add("odometry", feed.uses_odometry()).add("keyframes", stats.keyframes);
  run.method_summary.add("loop_closures", stats.loop_closures).add("near_links", stats.near_links);
  run.method_summary.add("loop_attempts", stats.loop_attempts).add("released_keyframes", stats.released_keyframes);
  run.method_summary.add("merged_nodes", stats.merged_nodes);
  run.method_summary.add("global_searches", stats.global_searches).add("global_closures", stats.global_closures);
  run.method_summary.add("large_closures", stats.large_closures).add("unconfirmed_closures", stats.unconfirmed_closures);
  run.method_summary.add("final_search_closures", stats.final_search_closures)
      .add("rejected_large_closures", stats.rejected_large_closures)
      .add("contradicted_large_closures", stats.contradicted_large_closures);
  run.method_summary.add("global_search_s", stats.global_search_seconds);
  if (stats.unconfirmed_closures > 0) {  // graph SLAM could not decide: say so instead of bending the map
    run.warnings.push_back(fmt::format("graph: {} large loop corrections found but not confirmed by a second keyframe "
                                       "were left out; a loop may be left open",
                                       stats.unconfirmed_closures));
  }
  if (stats.rejected_large_closures > 0) {  // the same: a loop left open rather than one closed wrong
    run.warnings.push_back(fmt::format("graph: {} large loop corrections were refused: each contradicted more loop "
                                       "closures already in the graph than agreed with it (a repeated structure, or a "
                                       "loop left open)",
                                       stats.rejected_large_closures));
  }
  run.method_summary.add("optimizations", stats.optimizations).add("sequential_failures", stats.sequential_failures);
  run.method_summary.add("stuck_matches", slam.stuck_matches());
  run.method_summary.add("scan_gaps", stats.gaps).add("gaps_tracked_through", stats.gaps_tracked_through);
  run.method_summary.add("optimization_iterations", stats.optimization_iterations)
      .add("deferred_optimizations", stats.deferred_optimizations)
      .add("local_optimizations", stats.local_optimizations);
  run.method_summary.add("optimization_s", stats.optimization_seconds).add("final_chi2", chi2(slam.graph()));
  if (feed.uses_odometry()) {
    report_odometry(run, slam.odometry_stats());
    run.method_summary.add("odometry_edges", stats.odometry_edges);
    if (config.odometry_edges) {
      run.method_summary.merge(fusion_report(stats.fusion, slam.odometry_noise()));
    } else if (config.tracking.prior_from_motion_noise) {
      run.method_summary.merge(odometry_noise_report(slam.odometry_noise()));
    }
    if (const OdometryCalibration* calibration = slam.odometry_calibration()) {
      run.method_summary.merge(calibration_report(*calibration));
    }
  }
  return run;
}

// Rao-Blackwellized particle filter (slam/rbpf, GMapping-class): the trajectory is the best
// particle's path, one pose per scan (scans between updates follow the scan-matched odometry).
// It needs a motion input: without wheel odometry, Hector's (run_method).
MappingRun map_with_rbpf(const MapJobOptions& options, const OdometryFeed& feed) {
  check(feed.uses_odometry(), "map: rbpf needs a motion input");
  RbpfConfig config = read_method_preset(options.config, "rbpf", RbpfConfig{});
  // The learnt prior weighs the odometry as a measurement of its own. Hector's poses (hector+rbpf,
  // rbpf without wheel odometry) come from the same scans, so how well they agree with the matches
  // says nothing of their noise: the fixed weak prior there.
  if (!feed.is_own_sensor()) config.scan_odometry_prior_from_motion_noise = false;
  // Across a gap Hector's poses are Hector's search's of the same scans: the filter's own search
  // would only add its new map's drift (ACES with 198 s of scans removed, hector+rbpf: 0.299 m over
  // all relations without it, 0.566 m with it).
  if (!feed.is_own_sensor()) config.relocalization.enabled = false;
  if (options.particles) config.particles = *options.particles;
  if (options.seed) config.seed = *options.seed;
  if (options.threads) config.threads = *options.threads;
  if (options.resolution) config.map.grid.resolution = *options.resolution;
  RbpfSlam slam(config);
  MappingRun run = run_over_scans(options, feed, "rbpf", [&](const LaserMessage& laser, const std::optional<SE2>& odometry) {
    return slam.add_scan(laser.scan, *odometry).T_map_robot;
  });
  run.trajectory = slam.trajectory();
  run.map = slam.occupancy_map();
  run.resolution = config.map.grid.resolution;
  report_gaps(run, slam.gap_stats());
  const RbpfStats& stats = slam.stats();
  run.method_summary.add("particles", config.particles).add("seed", static_cast<std::size_t>(config.seed));
  run.method_summary.add("threads", config.threads);
  run.method_summary.add("updates", stats.updates).add("resamplings", stats.resamplings);
  run.method_summary.add("neff_min", stats.neff_min).add("fallbacks", stats.fallbacks);
  run.method_summary.add("stuck_matches", stats.stuck_matches);
  if (config.scan_odometry_prior_from_motion_noise) {
    run.method_summary.add("odometry_noise_scale_translation", slam.scan_odometry_noise().translation_scale());
    run.method_summary.add("odometry_noise_scale_rotation", slam.scan_odometry_noise().rotation_scale());
    if (config.scan_odometry_calibration.window > 0.0) run.method_summary.merge(calibration_report(slam.scan_odometry_calibration()));
  }
  report_odometry(run, slam.odometry_stats());
  return run;
}

// map.png: the map cropped to what is known (20 cells of margin), the trajectory with its start and
// end, a scale bar, and the reference (already in the map frame) under the trajectory.
void write_outputs(const std::filesystem::path& dir, const MappingRun& run, const JsonObject& summary,
                   TrajectoryFormat format, const std::vector<SE2>& reference) {
  std::filesystem::create_directories(dir);
  write_map((dir / "map.yaml").string(), run.map, "map.pgm");
  const RenderOptions picture{.reference = reference, .crop_margin = 20, .scale_bar = true};
  write_png((dir / "map.png").string(), render_map(run.map, poses_of(run.trajectory), picture));
  write_trajectory((dir / "trajectory.txt").string(), run.trajectory, format);
  if (run.graph) write_g2o((dir / "graph.g2o").string(), to_pose_graph_file(*run.graph));
  if (run.dense_trajectory) write_trajectory((dir / "hector_trajectory.txt").string(), *run.dense_trajectory, format);
  if (run.sparse_trajectory) write_trajectory((dir / "sparse_trajectory.txt").string(), *run.sparse_trajectory, format);
  write_file_atomically((dir / "summary.json").string(), summary.dump());
}

// The reference trajectory in the run's map frame (the rigid motion of the ATE, fitted on the poses
// whose stamps both have), or nothing and a warning when fewer than two stamps match.
std::vector<SE2> reference_in_map(const Trajectory& reference, const Trajectory& trajectory,
                                  std::vector<std::string>& warnings) {
  try {
    const AteResult fit = absolute_trajectory_error(reference, trajectory);
    std::vector<SE2> poses;
    poses.reserve(reference.size());
    for (const StampedPose& stamped : reference) poses.push_back(fit.T_reference_estimate * stamped.pose);
    return poses;
  } catch (const Error& e) {
    warnings.push_back(std::string("map.png: the reference trajectory was not drawn: ") + e.what());
    return {};
  }
}

// The 2015 pipeline's first step (--odometry-source hector): Hector SLAM on the laser (and IMU)
// alone over the whole log, every scan, its jumps smoothed (slam/fusion/discontinuity_smoothing).
struct DenseHector {
  Trajectory trajectory;  // smoothed, robot frame, one pose per scan
  std::size_t jumps = 0;
  double cpu_s = 0.0;
};

DenseHector run_dense_hector(const MapJobOptions& options) {
  const RunClock clock;
  MapJobOptions hector = options;
  hector.config.clear();
  hector.scan_rate.reset();
  hector.resolution.reset();
  hector.levels.reset();
  const MappingRun run = map_with_hector(hector, OdometryFeed::none());
  SmoothingResult smoothed = smooth_discontinuities(run.trajectory);
  return {std::move(smoothed.trajectory), smoothed.jumps.size(), clock.cpu_seconds()};
}

// The odometry source asked for; rbpf's "none" is Hector's (the particle filter needs a motion
// input, and scan-to-scan matching alone measured far worse: 3.3 m against 0.019 m on Intel).
std::string odometry_source_of(const MapJobOptions& options, const std::string& method) {
  const std::string source = options.no_odometry ? std::string("none") : options.odometry_source;
  return method == "rbpf" && source == "none" ? "hector" : source;
}

OdometryFeed resolve_odometry_feed(const MapJobOptions& options, const std::string& source,
                                   std::optional<DenseHector>& hector) {
  if (source == "log") return {};
  if (source == "none") return OdometryFeed::none();
  if (source == "hector") {
    hector = run_dense_hector(options);
    return OdometryFeed::per_scan(hector->trajectory, "hector");
  }
  check(std::filesystem::exists(source),
        "map: --odometry-source must be log, none, hector or a trajectory file; '" + source + "' is none of them");
  Trajectory trajectory = read_any_trajectory(source).sorted_by_stamp();
  check(trajectory.size() >= 2, source + ": an odometry trajectory needs at least two poses");
  return OdometryFeed::from(std::move(trajectory), source);
}

// The sparse method of a chain ("hector+graph" -> "graph"), or the method itself.
std::string sparse_method(const std::string& method) {
  const std::string prefix = "hector+";
  return method.starts_with(prefix) ? method.substr(prefix.size()) : method;
}

MappingRun run_method(const std::string& method, const MapJobOptions& options, const OdometryFeed& feed) {
  if (method == "hector") return map_with_hector(options, feed);
  if (method == "graph") return map_with_graph(options, feed);
  if (method == "rbpf") return map_with_rbpf(options, feed);
  return map_with_odometry(options, feed);
}

// hector+graph, hector+rbpf (Kaijaluoto et al. 2015): Hector's smoothed dense trajectory is the
// odometry of the sparse method, which sees the time-based subset of the scans (3 Hz, the paper's,
// unless --scan-rate says otherwise); the sparse, globally consistent trajectory is then fused into
// the dense one (slam/fusion/trajectory_fusion). The map is the sparse method's.
MappingRun run_chain(const MapJobOptions& options) {
  check(options.odometry_source == "log" || options.odometry_source == "hector",
        "map: " + options.method + " takes its odometry from Hector; drop --odometry-source");
  check(!options.no_odometry, "map: " + options.method + " uses no wheel odometry already; drop --no-odometry");
  MapJobOptions sparse = options;
  sparse.odometry_source = "hector";
  if (!sparse.scan_rate) sparse.scan_rate = kChainScanRate;
  std::optional<DenseHector> hector;
  const OdometryFeed feed = resolve_odometry_feed(sparse, "hector", hector);
  MappingRun run = run_method(sparse_method(options.method), sparse, feed);
  FusionStats fusion;
  Trajectory fused = fuse_trajectories(hector->trajectory, run.trajectory, FusionConfig{}, &fusion);
  run.sparse_trajectory = std::move(run.trajectory);
  run.dense_trajectory = hector->trajectory;
  run.trajectory = std::move(fused);
  run.data_duration = run.trajectory.back().stamp - run.trajectory.front().stamp;
  JsonObject chain;
  chain.add("hector_cpu_s", hector->cpu_s).add("hector_jumps_smoothed", hector->jumps);
  chain.add("sparse_scans", run.sparse_trajectory->size()).add("sparse_used", fusion.sparse_used);
  chain.add("blended_segments", fusion.blended_segments).add("max_scale_change", fusion.max_scale_change);
  run.method_summary.add("odometry_source", "hector").add("chain", chain);
  return run;
}

// The method's per-scan poses smoothed with the odometry they came with (slam/fusion/
// odometry_smoothing.hpp), and what it found into the summary. Only an odometry that is a sensor
// of its own (the log's, a trajectory file's): Hector's, the laser's, would share the method's errors.
void smooth_run_with_odometry(MappingRun& run, const MapJobOptions& options) {
  OdometrySmoothingConfig config;
  config.enabled = options.odometry_smoothing;
  OdometrySmoothingStats stats;
  const std::vector<SE2> smoothed =
      smooth_with_odometry(poses_of(run.trajectory), run.odometry, config, &stats, &run.scan_odometry);
  if (stats.applied) run.trajectory = with_poses(run.trajectory, smoothed);
  run.method_summary.add("odometry_smoothing", smoothing_report(stats));
}

MappingRun run_method(const MapJobOptions& options) {
  if (options.method.starts_with("hector+")) return run_chain(options);
  std::optional<DenseHector> hector;
  const std::string source = odometry_source_of(options, options.method);
  const OdometryFeed feed = resolve_odometry_feed(options, source, hector);
  MappingRun run = run_method(options.method, options, feed);
  if (smoothed_with_odometry(options, feed)) smooth_run_with_odometry(run, options);
  run.method_summary.add("odometry_source", source);
  if (hector) run.method_summary.add("hector_cpu_s", hector->cpu_s).add("hector_jumps_smoothed", hector->jumps);
  return run;
}

}  // namespace

const std::vector<std::string>& map_methods() {
  static const std::vector<std::string> methods{"odometry", "hector", "graph", "rbpf", "hector+graph", "hector+rbpf"};
  return methods;
}

MapJobResult run_map_job(const MapJobOptions& options) {
  const auto& methods = map_methods();
  check(std::find(methods.begin(), methods.end(), options.method) != methods.end(),
        "map: unknown method '" + options.method + "' (known: odometry, hector, graph, rbpf, hector+graph, hector+rbpf)");
  check(!options.scan_rate || (std::isfinite(*options.scan_rate) && *options.scan_rate > 0.0 && *options.scan_rate <= 1000.0),
        "map: --scan-rate must be in (0, 1000] Hz");
  check(!options.particles || (*options.particles >= 1 && *options.particles <= 10000), "map: --particles must be in [1, 10000]");
  check(!options.resolution || (*options.resolution > 0.0 && *options.resolution <= 10.0), "map: --resolution must be in (0, 10] m");
  check(!options.levels || (*options.levels >= 1 && *options.levels <= 16), "map: --levels must be in [1, 16]");
  trajectory_format_from_name(options.trajectory_format);  // checked before the work
  check(options.trajectory_frame == "robot" || options.trajectory_frame == "sensor",
        "map: --trajectory-frame must be robot or sensor");
  const std::optional<Trajectory> reference =
      options.reference.empty() ? std::nullopt : std::optional<Trajectory>(read_any_trajectory(options.reference));
  const RunClock clock;
  MapJobOptions resolved = options;  // with the odometry time offset the reader compensates
  const bool log_odometry = odometry_source_of(options, options.method) == "log" && !options.method.starts_with("hector+");
  const OdometryTimeOffsetChoice time_offset = resolve_odometry_time_offset(
      options.log, log_odometry ? options.odometry_time_offset : "off", resolved.input, options.quiet);
  MappingRun run = run_method(resolved);
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
  summary.merge(odometry_time_offset_json(time_offset));
  summary.add("peak_rss_mb", peak_rss_mb());
  const std::vector<SE2> drawn_reference = reference ? reference_in_map(*reference, run.trajectory, run.warnings) : std::vector<SE2>();
  summary.add("warnings", run.warnings);
  if (!options.mcap.empty()) write_run_mcap(options.mcap, options.log, resolved.input, false, run.map, run.trajectory);
  if (options.trajectory_frame == "sensor") {  // the laser's pose: what a benchmark's relations may describe
    const auto to_sensor = [&](Trajectory& trajectory) {
      Trajectory sensor;
      sensor.reserve(trajectory.size());
      for (const StampedPose& stamped : trajectory) sensor.push_back(stamped.stamp, stamped.pose * run.T_robot_sensor);
      trajectory = std::move(sensor);
    };
    to_sensor(run.trajectory);
    if (run.dense_trajectory) to_sensor(*run.dense_trajectory);
    if (run.sparse_trajectory) to_sensor(*run.sparse_trajectory);
  }
  write_outputs(options.out_dir, run, summary, trajectory_format_from_name(options.trajectory_format), drawn_reference);
  return {std::move(run.map), std::move(run.trajectory), std::move(summary)};
}

}  // namespace slam2d::cli
