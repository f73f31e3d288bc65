// SPDX-License-Identifier: BSD-3-Clause
// slam2d match LOG --target I --source J: one scan match between two front-laser scans of a log,
// by index (0-based, in file order), with any matcher: the relative pose of scan J's robot in scan
// I's robot frame, how the iteration ended, its covariance and the degeneracy verdict
// (match_report.hpp). The guess is the relative odometry pose unless --guess gives one.

#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <variant>

#include "commands.hpp"
#include "json.hpp"
#include "match_report.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/methods/matcher_registry.hpp"
#include "slam2d/registration/scan_odometry.hpp"

namespace slam2d::cli {
namespace {

struct MatchOptions {
  std::string log;
  std::size_t target = 0;
  std::size_t source = 0;
  std::string guess;  // x,y,theta (m, m, rad); empty: the relative odometry pose
  std::string matcher = "pl-icp";
  std::string config;  // a preset .yaml for the matcher
  LogReaderOptions input;
  bool json = false;
};

struct LoggedScan {
  LaserScan scan;
  std::optional<SE2> odom_pose;  // T_odom_robot, when the log has it
};

SE2 parse_pose(const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    check(used > 0 && used == item.size() && std::isfinite(value),
          fmt::format("match: --guess expects x,y,theta (m, m, rad), got '{}'", text));
    values.push_back(value);
  }
  check(values.size() == 3, fmt::format("match: --guess expects x,y,theta (m, m, rad), got '{}'", text));
  return SE2(values[0], values[1], values[2]);
}

// Front-laser scans `target` and `source` of the log (reading stops after the later one).
std::pair<LoggedScan, LoggedScan> read_pair(const MatchOptions& options) {
  LogReader reader(options.log, options.input);
  const std::size_t last = std::max(options.target, options.source);
  std::optional<LoggedScan> target, source;
  std::size_t index = 0;
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    const LoggedScan scan{laser->scan, laser->has_poses ? std::optional<SE2>(laser->odom_pose) : std::nullopt};
    if (index == options.target) target = scan;
    if (index == options.source) source = scan;
    if (index++ == last) break;
  }
  print_reader_warnings(reader);
  check(index > last, fmt::format("{}: scan index {} out of range: the log has {} front-laser scans (0 .. {})", reader.path(),
                                  last, index, index == 0 ? std::string("none") : std::to_string(index - 1)));
  return {*target, *source};
}

// The scan's points in its sensor frame with readings at or beyond max_range dropped (as scan
// odometry does).
PointCloud2 usable_cloud(const LaserScan& scan, double max_range) {
  PointCloud2 cloud = to_point_cloud(scan, ScanFrame::kSensor).cloud;
  std::erase_if(cloud.points, [&](const Point2& p) { return !(p.norm() < max_range); });
  cloud.normals.clear();
  cloud.weights.clear();
  return cloud;
}

JsonObject pose_json(const SE2& pose) {
  JsonObject json;
  json.add("x", pose.x()).add("y", pose.y()).add("theta", pose.theta()).add("theta_deg", rad_to_deg(pose.theta()));
  return json;
}

void run_match(const MatchOptions& options) {
  check(options.target != options.source, "match: --target and --source must be different scans");
  const Matcher matcher =
      options.config.empty() ? make_matcher(options.matcher) : make_matcher(options.matcher, ConfigNode::load(options.config));
  const auto [target, source] = read_pair(options);
  // The guess between the robots, then between the sensors.
  std::string guess_from = "--guess";
  SE2 guess;
  if (!options.guess.empty()) {
    guess = parse_pose(options.guess);
  } else if (target.odom_pose && source.odom_pose) {
    guess = target.odom_pose->between(*source.odom_pose);
    guess_from = "odometry";
  } else {
    guess_from = "none (the log has no odometry)";
  }
  const double max_range = options.input.carmen.geometry.range_max.value_or(ScanOdometryConfig{}.max_range);
  const PointCloud2 target_cloud = usable_cloud(target.scan, max_range);
  const PointCloud2 source_cloud = usable_cloud(source.scan, max_range);
  check(target_cloud.size() >= 3 && source_cloud.size() >= 3,
        fmt::format("{}: scan {} has {} usable points and scan {} has {}; a match needs 3", options.log, options.target,
                    target_cloud.size(), options.source, source_cloud.size()));
  const SE2 guess_sensor = target.scan.T_robot_sensor.inverse() * guess * source.scan.T_robot_sensor;
  const MatchResult match = match_between_robots(matcher(target_cloud, source_cloud, guess_sensor),
                                                 target.scan.T_robot_sensor, source.scan.T_robot_sensor);

  JsonObject json;
  json.add("log", options.log).add("matcher", options.config.empty() ? options.matcher : options.matcher + " (" + options.config + ")");
  json.add("target", options.target).add("source", options.source);
  json.add("target_stamp", target.scan.stamp).add("source_stamp", source.scan.stamp);
  json.add("target_points", target_cloud.size()).add("source_points", source_cloud.size());
  json.add("guess_from", guess_from).add("guess", pose_json(guess));
  json.add("pose", pose_json(match.T_target_source));
  json.add("converged", match.converged).add("iterations", match.iterations).add("inliers", match.inliers);
  json.add("residual", match.residual);
  json.add("covariance", covariance_json(match.covariance));
  json.add("degeneracy", degeneracy_json(match));
  std::fputs(options.json ? json.dump().c_str() : json.text().c_str(), stdout);
}

}  // namespace

void add_match_command(CLI::App& app) {
  auto options = std::make_shared<MatchOptions>();
  CLI::App* command = app.add_subcommand("match", "Match two scans of a log: pose, covariance and degeneracy");
  command->add_option("log", options->log, "CARMEN log (plain or .gz) or bag")->required();
  command->add_option("--target", options->target, "Index of the target scan (0-based, front-laser scans in file order)")
      ->required();
  command->add_option("--source", options->source, "Index of the source scan (matched into the target's frame)")->required();
  command->add_option("--guess", options->guess,
                      "Initial guess x,y,theta (m, m, rad) of the source robot in the target robot's frame "
                      "(default: the relative odometry pose)");
  command->add_option("--matcher", options->matcher, "Matcher name")
      ->check(CLI::IsMember(matcher_names()))
      ->capture_default_str();
  command->add_option("--config", options->config, "Matcher preset (.yaml, e.g. configs/pl-icp.yaml)");
  add_sensor_options(command, options->input, "m: readings at or above are dropped (default 30, as odometry)");
  command->add_flag("--json", options->json, "Print the result as JSON");
  command->callback([options] { run_match(*options); });
}

}  // namespace slam2d::cli
