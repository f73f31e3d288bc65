// SPDX-License-Identifier: BSD-3-Clause
// slam2d odometry LOG --matcher NAME --out TRAJ: scan-to-scan odometry over a whole log with any
// matcher (registration/scan_odometry.hpp), one trajectory line per front-laser scan; with
// --covariance-csv FILE also each scan's match: its covariance and degeneracy, and the keyframe it
// was matched against (match_report.hpp).

#include <fmt/core.h>

#include <cstdio>
#include <filesystem>
#include <optional>
#include <variant>

#include "commands.hpp"
#include "json.hpp"
#include "match_report.hpp"
#include "odometry_report.hpp"
#include "progress.hpp"
#include "run_stats.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/eval/statistics.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/methods/matcher_registry.hpp"
#include "slam2d/registration/scan_odometry.hpp"

namespace slam2d::cli {
namespace {

struct OdometryOptions {
  std::string log;
  std::string matcher = "pl-icp";
  std::string config;  // a preset .yaml for the matcher
  std::string out;
  std::string covariance_csv;  // per-scan covariance and degeneracy; empty: none
  std::string trajectory_format = "text";  // text | tum
  std::optional<double> keyframe;            // m; 0: match every scan against the previous one
  std::optional<double> keyframe_angle_deg;  // deg
  std::optional<std::size_t> local_map;      // keyframes the scan is matched against
  LogReaderOptions input;                      // CARMEN geometry overrides, bag topics and frames
  bool no_odometry = false;
  std::string odometry_time_offset = "auto";  // auto | off | seconds (sensor_options.hpp)
  bool json = false;
  bool quiet = false;
};

Matcher configured_matcher(const OdometryOptions& options) {
  if (options.config.empty()) return make_matcher(options.matcher);
  const ConfigNode config = ConfigNode::load(options.config);
  return make_matcher(options.matcher, config);
}

ScanOdometryConfig odometry_config(const OdometryOptions& options) {
  ScanOdometryConfig config;
  if (options.keyframe) {
    config.keyframe_distance = *options.keyframe;
    if (*options.keyframe == 0.0) config.keyframe_angle = 0.0;
  }
  if (options.keyframe_angle_deg) config.keyframe_angle = deg_to_rad(*options.keyframe_angle_deg);
  if (options.local_map) config.local_map_keyframes = *options.local_map;
  if (options.input.carmen.geometry.range_max) config.max_range = *options.input.carmen.geometry.range_max;
  validate(config);
  return config;
}

// What the matches of a run said about their certainty: the --covariance-csv rows and the figures
// of the summary (over the matches that passed the gate; degenerate ones over every match).
class CovarianceRecord {
 public:
  explicit CovarianceRecord(bool enabled) : enabled_(enabled) {
    if (enabled_) csv_ = covariance_csv_header();
  }

  void add(const ScanOdometry& odometry, const LaserScan& scan) {
    if (!enabled_) return;
    const std::size_t index = odometry.stats().scans - 1;
    if (index == 0) {
      csv_ += covariance_csv_row(index, scan.stamp, "first", nullptr);
      return;
    }
    if (!odometry.last_matched()) {
      csv_ += covariance_csv_row(index, scan.stamp, "too_few_points", nullptr);
      return;
    }
    const MatchResult match =
        match_between_robots(odometry.last_match(), odometry.last_target_T_robot_sensor(), scan.T_robot_sensor);
    csv_ += covariance_csv_row(index, scan.stamp, odometry.last_accepted() ? "matched" : "failed", &match,
                               odometry.last_target_index());
    if (match.degenerate) ++degenerate_;
    if (odometry.last_accepted()) {
      trans_sigmas_.push_back(translation_sigma(match.covariance));
      rot_sigmas_deg_.push_back(rad_to_deg(rotation_sigma(match.covariance)));
    }
  }

  void write(const std::string& path) const {
    const std::filesystem::path out(path);
    if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
    write_file_atomically(path, csv_);
  }

  JsonObject summary(const std::string& path) const {
    JsonObject json;
    const auto stat = [](const std::vector<double>& values, double p) {
      return values.empty() ? std::nullopt : std::optional<double>(percentile(values, p));
    };
    json.add("covariance_csv", path).add("degenerate_scans", degenerate_);
    json.add("sigma_trans_median_m", stat(trans_sigmas_, 50)).add("sigma_trans_p95_m", stat(trans_sigmas_, 95));
    json.add("sigma_theta_median_deg", stat(rot_sigmas_deg_, 50)).add("sigma_theta_p95_deg", stat(rot_sigmas_deg_, 95));
    return json;
  }

 private:
  bool enabled_;
  std::string csv_;
  std::size_t degenerate_ = 0;
  std::vector<double> trans_sigmas_;    // m
  std::vector<double> rot_sigmas_deg_;  // deg
};

void run_odometry(const OdometryOptions& options) {
  ScanOdometry odometry(configured_matcher(options), odometry_config(options));
  const RunClock clock;
  LogReaderOptions input = options.input;
  const OdometryTimeOffsetChoice time_offset = resolve_odometry_time_offset(
      options.log, options.no_odometry ? "off" : options.odometry_time_offset, input, options.quiet);
  LogReader reader(options.log, input);
  Progress progress("odometry", options.quiet);
  CovarianceRecord covariance(!options.covariance_csv.empty());
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    const bool use_odometry = laser->has_poses && !options.no_odometry;
    odometry.add(laser->scan, use_odometry ? std::optional<SE2>(laser->odom_pose) : std::nullopt);
    covariance.add(odometry, laser->scan);
    if (odometry.stats().scans % 256 == 0) {
      progress.update(reader.progress(), fmt::format("{} scans, {} failures", odometry.stats().scans, odometry.stats().failures));
    }
  }
  progress.finish();
  print_reader_warnings(reader);
  const double cpu = clock.cpu_seconds();
  const Trajectory& trajectory = odometry.trajectory();
  check(!trajectory.empty(), reader.path() + ": no front-laser scans in the log");
  const std::filesystem::path out(options.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  write_trajectory(options.out, trajectory, trajectory_format_from_name(options.trajectory_format));
  if (!options.covariance_csv.empty()) covariance.write(options.covariance_csv);

  const ScanOdometryStats& stats = odometry.stats();
  const double matches = static_cast<double>(std::max<std::size_t>(stats.matches, 1));
  const double duration = trajectory.back().stamp - trajectory.front().stamp;
  JsonObject summary;
  summary.add("matcher", options.config.empty() ? options.matcher : options.matcher + " (" + options.config + ")");
  summary.add("log", options.log).add("scans", stats.scans).add("matches", stats.matches).add("keyframes", stats.keyframes);
  summary.add("cpu_s", cpu).add("us_per_match", 1e6 * stats.matcher_seconds / matches);
  summary.add("mean_iterations", static_cast<double>(stats.total_iterations) / matches).add("failures", stats.failures);
  summary.add("data_duration_s", duration).add("realtime_factor", cpu > 0.0 ? std::optional<double>(duration / cpu) : std::nullopt);
  summary.add("odometry_guess", !options.no_odometry).add("trajectory", options.out);
  summary.add("odometry_steps_reversed", reader.stats().odometry_steps_reversed);
  summary.merge(odometry_time_offset_json(time_offset));
  if (!options.covariance_csv.empty()) summary.merge(covariance.summary(options.covariance_csv));
  std::vector<std::string> warnings = reader_warnings(reader);
  if (!options.no_odometry) {
    summary.merge(odometry_report(odometry.odometry_stats()));
    // The fusion's counts only when it ran (fuse_odometry): zeros would read as "never disagreed".
    if (odometry.config().fuse_odometry) summary.merge(fusion_report(stats.fusion, odometry.odometry_noise()));
    for (std::string& warning : odometry_warnings(odometry.odometry_stats())) warnings.push_back(std::move(warning));
  }
  summary.add("warnings", warnings);
  std::fputs(options.json ? summary.dump().c_str() : summary.text().c_str(), stdout);
}

}  // namespace

void add_odometry_command(CLI::App& app) {
  auto options = std::make_shared<OdometryOptions>();
  CLI::App* command = app.add_subcommand("odometry", "Scan-to-scan odometry over a log with a scan matcher");
  command->add_option("log", options->log, "CARMEN log (plain or .gz)")->required();
  command->add_option("--matcher", options->matcher, "Matcher name")
      ->check(CLI::IsMember(matcher_names()))
      ->capture_default_str();
  command->add_option("--config", options->config, "Matcher preset (.yaml, e.g. configs/pl-icp.yaml)");
  command->add_option("--out", options->out, "Trajectory file (one line per scan: stamp x y theta)")->required();
  command->add_option("--covariance-csv", options->covariance_csv,
                      "CSV, one row per scan: its match against the keyframe (pose, covariance, degeneracy and its "
                      "measure, in the keyframe's robot frame) and that keyframe's scan index (target)");
  command->add_option("--keyframe", options->keyframe,
                      "m the robot moves before the next keyframe (default 0.1; 0: match against the previous scan)");
  command->add_option("--keyframe-angle", options->keyframe_angle_deg, "deg the robot turns before the next keyframe (default 10)");
  command->add_option("--local-map", options->local_map,
                      "keyframes the scan is matched against, the newest and those before it (default 2; 1: the keyframe alone)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1000}));
  add_sensor_options(command, options->input,
                     "m: readings at or above are dropped (default: 30 for matching, and the reader's no-return "
                     "threshold: the log's PARAM, else 80)");
  command->add_flag("--no-odometry", options->no_odometry, "Ignore the log's odometry (guess: constant velocity)");
  add_odometry_time_offset_option(command, options->odometry_time_offset);
  command->add_option("--format", options->trajectory_format, "The trajectory as slam2d text (t x y theta) or tum (evo's format)")
      ->check(CLI::IsMember({"text", "tum"}))
      ->capture_default_str();
  command->add_flag("--json", options->json, "Print the summary as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_odometry(*options); });
}

}  // namespace slam2d::cli
