// SPDX-License-Identifier: BSD-3-Clause
// slam2d localize LOG --map MAP.yaml --method markov|ekf|mcl|hybrid: localization in a known map
// (src/slam2d/localization, docs/methods/localization.md), one trajectory line per front-laser
// scan, and a summary with the convergence and recovery times and the cost per update.

#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "commands.hpp"
#include "json.hpp"
#include "localize_job.hpp"
#include "odometry_report.hpp"
#include "progress.hpp"
#include "run_mcap_output.hpp"
#include "run_stats.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/grid/render.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/localization/motion_model.hpp"
#include "slam2d/localization/session.hpp"

namespace slam2d::cli {
namespace {

// --png: the map cropped to what is known, the run on it (lost stretches in their own colour), the
// last estimate's 2-sigma position ellipse and, for MCL, its particles at the end.
RgbImage run_picture(const OccupancyMap& map, const Trajectory& trajectory, const LocalizationSession& session,
                     const LocalizationEstimate& last, const Localizer& localizer) {
  RenderOptions picture{.crop_margin = 20, .scale_bar = true};
  for (const bool localized : session.localized()) picture.lost.push_back(!localized);
  picture.end_covariance = last.covariance.topLeftCorner<2, 2>();
  if (const auto* mcl = dynamic_cast<const MonteCarloLocalization*>(&localizer)) {
    for (const SE2& particle : mcl->particles()) picture.points.push_back(particle.translation());
  }
  return render_map(map, poses_of(trajectory), picture);
}

// The run's poses smoothed with the log's odometry (slam/fusion/odometry_smoothing.hpp) over each
// stretch where the localizer was localized: a localizer's pose jitters against the map from scan
// to scan, and the odometry is smooth from one scan to the next. The raw wheel odometry, not the
// one the localizer saw: within a stall that one is the localizer's own match, and a kidnap is
// not the robot's motion. The filter's own estimates (online, the Python Localizer's) stay as they are.
Trajectory smoothed_run(const LocalizationSession& session, const std::vector<SE2>& odometry, bool enabled,
                        OdometrySmoothingStats& stats) {
  OdometrySmoothingConfig config;
  config.enabled = enabled;
  const std::vector<SE2> smoothed =
      smooth_trusted_with_odometry(poses_of(session.trajectory()), odometry, session.localized(), config, &stats);
  return stats.applied ? with_poses(session.trajectory(), smoothed) : session.trajectory();
}

void run_localize(const LocalizeOptions& options) {
  const RunClock clock;
  const OccupancyMap occupancy = read_map(options.map);
  const LocalizationMap map(occupancy);
  JsonObject settings;
  std::unique_ptr<Localizer> localizer = make_localizer(options, map, settings);
  std::optional<Kidnap> kidnap;
  if (options.kidnap_at) {
    const std::vector<double> by = parse_triple(options.kidnap_by, "--kidnap-by");
    kidnap = Kidnap{.at = *options.kidnap_at, .by = SE2(by[0], by[1], deg_to_rad(by[2]))};
  }
  LocalizationSession session(*localizer, kidnap, OdometryGuardConfig{}, &map);
  LogReaderOptions input = options.input;  // with the odometry time offset the reader compensates
  const OdometryTimeOffsetChoice time_offset =
      resolve_odometry_time_offset(options.log, options.odometry_time_offset, input, options.quiet);
  LogReader reader(options.log, input);
  Progress progress("localize", options.quiet);
  LocalizationEstimate last;
  std::vector<SE2> odometry;
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    if (!laser->has_poses) {
      throw ParseError(reader.path(), laser->line, laser->type + " carries no odometry pose; localization needs odometry");
    }
    last = session.add(laser->odom_pose, laser->scan);
    odometry.push_back(laser->odom_pose);
    if (session.summary().scans % 256 == 0) {
      progress.update(reader.progress(), fmt::format("{} scans, localized: {}", session.summary().scans,
                                                     session.localized().back() ? "yes" : "no"));
    }
  }
  progress.finish();
  print_reader_warnings(reader);
  const LocalizationRunSummary& run = session.summary();
  check(run.scans > 0, reader.path() + ": no front-laser scans in the log");
  const std::filesystem::path out(options.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  OdometrySmoothingStats smoothing;
  const Trajectory trajectory = smoothed_run(session, odometry, options.odometry_smoothing, smoothing);
  write_trajectory(options.out, trajectory, trajectory_format_from_name(options.trajectory_format));
  if (!options.mcap.empty()) write_run_mcap(options.mcap, options.log, input, true, occupancy, trajectory);
  if (!options.png.empty()) write_png(options.png, run_picture(occupancy, trajectory, session, last, *localizer));

  const double cpu = clock.cpu_seconds();
  JsonObject summary;
  summary.add("method", options.method).add("log", options.log).add("map", options.map);
  if (!options.config.empty()) summary.add("config", options.config);
  summary.merge(settings);
  summary.add("odometry_steps_reversed", reader.stats().odometry_steps_reversed);
  summary.merge(odometry_time_offset_json(time_offset));
  summary.merge(odometry_report(session.odometry_stats()));
  std::vector<std::string> warnings = reader_warnings(reader);
  for (std::string& warning : odometry_warnings(session.odometry_stats())) warnings.push_back(std::move(warning));
  summary.add("global", options.global).add("scans", run.scans).add("sensor_updates", run.sensor_updates);
  summary.add("cpu_s", cpu).add("localizer_cpu_s", run.localizer_cpu_s);
  summary.add("us_per_update", 1e6 * run.localizer_cpu_s / static_cast<double>(std::max<std::size_t>(run.sensor_updates, 1)));
  if (const MotionNoiseLearner* noise = localizer->motion_noise(); noise != nullptr && noise->stretches() > 0) {
    summary.add("odometry_noise_stretches", noise->stretches());
    summary.add("odometry_noise_scale_translation", noise->translation_scale());
    summary.add("odometry_noise_scale_rotation", noise->rotation_scale());
    summary.merge(calibration_report(noise->calibration()));
  }
  summary.add("odometry_smoothing", smoothing_report(smoothing));
  summary.add("converged_at_s", run.converged_at_s);
  summary.add("localized_fraction", static_cast<double>(run.localized_scans) / static_cast<double>(run.scans));
  summary.add("lost_events", run.lost_events);
  summary.add("kidnapped_at_s", run.kidnapped_at_s).add("recovered_after_s", run.recovered_after_s);
  summary.add("data_duration_s", run.data_duration_s);
  summary.add("realtime_factor", cpu > 0.0 ? std::optional<double>(run.data_duration_s / cpu) : std::nullopt);
  summary.add("peak_rss_mb", peak_rss_mb()).add("trajectory", options.out);
  summary.add("warnings", warnings);
  std::fputs(options.json ? summary.dump().c_str() : summary.text().c_str(), stdout);
}

}  // namespace

void add_localize_command(CLI::App& app) {
  auto options = std::make_shared<LocalizeOptions>();
  CLI::App* command = app.add_subcommand("localize", "Localization in a known map: Markov grid, EKF, Monte Carlo, hybrid");
  command->add_option("log", options->log, "CARMEN log (plain or .gz), ROS 1 bag, MCAP file or rosbag2 folder, with odometry")->required();
  command->add_option("--map", options->map, "Map YAML (ROS map_server format, e.g. from slam2d map)")->required();
  command->add_option("--method", options->method, "Localization method")
      ->check(CLI::IsMember({"markov", "ekf", "mcl", "hybrid"}))
      ->capture_default_str();
  command->add_option("--initial", options->initial, "Initial pose x,y,theta (m, m, rad) in the map frame");
  command->add_option("--initial-sigma", options->initial_sigma, "Standard deviations of the initial pose (m, m, rad)")
      ->capture_default_str();
  command->add_flag("--global", options->global, "Global localization from a uniform prior (not ekf)");
  command->add_option("--config", options->config,
                      "A method preset (configs/<method>.yaml; `slam2d config dump METHOD` prints the defaults); the flags below override it")
      ->check(CLI::ExistingFile);
  command->add_option("--particles", options->particles, "mcl: maximum particle count (default 5000; KLD-sampling adapts below it)");
  command->add_option("--sensor", options->sensor, "mcl: sensor model (default likelihood-field)")
      ->check(CLI::IsMember({"likelihood-field", "beam"}));
  command->add_option("--seed", options->seed, "mcl: random seed (default 1)");
  command->add_option("--kidnap-at", options->kidnap_at, "s after the first scan: corrupt the odometry once (kidnap test)");
  command->add_option("--kidnap-by", options->kidnap_by, "The kidnap's extra motion dx,dy,dtheta (m, m, deg; robot frame)")
      ->capture_default_str();
  add_sensor_options(command, options->input);
  add_odometry_time_offset_option(command, options->odometry_time_offset);
  command->add_option("--out", options->out, "Trajectory file (one line per scan: stamp x y theta)")->required();
  command->add_option("--png", options->png,
                      "Also draw the run on the map: localized stretches red, lost ones orange, the final 2-sigma "
                      "ellipse, and MCL's particles");
  command->add_option("--mcap", options->mcap,
                      "Also write the run for Foxglove: map, path, poses, scans (and in the map frame), tf (MCAP, ROS 2 types)");
  command->add_option("--format", options->trajectory_format, "The trajectory as slam2d text (t x y theta) or tum (evo's format)")
      ->check(CLI::IsMember({"text", "tum"}))
      ->capture_default_str();
  command->add_flag("!--no-odometry-smoothing", options->odometry_smoothing,
                    "Write the localizer's own per-scan estimates, not smoothed with the odometry over its localized stretches");
  command->add_flag("--json", options->json, "Print the summary as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_localize(*options); });
}

}  // namespace slam2d::cli
