// SPDX-License-Identifier: BSD-3-Clause
#include "sensor_options.hpp"

#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "progress.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d::cli {

namespace {

// A finite number in (low, high]; `low_open` false makes it [low, high]; an infinite `high`, no upper bound.
CLI::Validator number_in(double low, double high, bool low_open, const std::string& unit) {
  const std::string range = std::isinf(high) ? fmt::format("{}{}, inf)", low_open ? "(" : "[", low)
                                              : fmt::format("{}{}, {}]", low_open ? "(" : "[", low, high);
  return CLI::Validator(
      [=](const std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) || value > high ||
            (low_open ? value <= low : value < low)) {
          return "must be a finite number in " + range + " " + unit + ", got " + text;
        }
        return {};
      },
      unit + " in " + range);
}

// An option whose value, times `scale`, is stored in `target`.
void add_number(CLI::App* command, const std::string& name, std::optional<double>& target, double scale,
                const CLI::Validator& validator, const std::string& help) {
  command->add_option_function<double>(name, [&target, scale](double value) { target = scale * value; }, help)
      ->check(validator);
}

}  // namespace

void add_sensor_options(CLI::App* command, CarmenReaderOptions& options, const std::string& range_max_help) {
  const double radians_per_degree = deg_to_rad(1.0);
  add_number(command, "--fov", options.geometry.field_of_view, radians_per_degree, number_in(0.0, 360.0, true, "deg"),
             "deg: the laser's field of view, steps x increment (default: a bag's LaserScan as declared; CARMEN: the PARAM lines checked against the beam count, else 180)");
  add_number(command, "--angle-min", options.geometry.angle_min, radians_per_degree, number_in(-360.0, 360.0, false, "deg"),
             "deg: the angle of the first beam (default: as declared, else -fov / 2)");
  add_number(command, "--angle-increment", options.geometry.angle_increment, radians_per_degree, number_in(0.0, 360.0, true, "deg"),
             "deg: the angle between beams (default: as declared; CARMEN: the PARAM, else fov / steps)");
  add_number(command, "--range-max", options.geometry.range_max, 1.0,
             number_in(0.0, std::numeric_limits<double>::infinity(), true, "m"),
             range_max_help.empty() ? "m: readings at or above are no return (default: as declared; CARMEN: the PARAM, else 80)"
                                    : range_max_help);
  command->add_flag_callback("--raw-odometry", [&options] { options.repair_reverse_odometry = false; },
                             "Keep the odometry as logged: do not reverse the travel of steps that move forward while ODOM tv < 0 "
                             "(odometry that integrates reversing as forward driving, like FR079's)");
}

std::vector<std::string> reader_warnings(const CarmenReader& reader) {
  std::vector<std::string> warnings;
  for (const OldLaserGeometry& geometry : reader.stats().old_laser_geometries) {
    for (const std::string& warning : geometry.warnings) {
      warnings.push_back(fmt::format("{}:{}: warning: {} geometry, {} beams: {}", reader.path(), geometry.first_line,
                                     geometry.rear ? "RLASER" : "FLASER", geometry.beams, warning));
    }
  }
  if (reader.stats().odometry_steps_reversed > 0) {
    warnings.push_back(fmt::format(
        "{}: warning: the odometry integrates reversing as forward driving: {} steps that moved forward while ODOM tv < 0 "
        "were repaired (--raw-odometry keeps them)",
        reader.path(), reader.stats().odometry_steps_reversed));
  }
  return warnings;
}

void print_reader_warnings(const CarmenReader& reader) {
  for (const std::string& warning : reader_warnings(reader)) std::fputs((warning + "\n").c_str(), stderr);
}

void add_sensor_options(CLI::App* command, LogReaderOptions& options, const std::string& range_max_help) {
  add_sensor_options(command, options.carmen, range_max_help);
  command->add_option("--scan-topic", options.bag.scan_topic, "bags: the LaserScan topic (default: the only one)");
  command->add_option("--odom-topic", options.bag.odom_topic,
                      "bags: the Odometry topic (default: the only one, else odom -> base on /tf)");
  command->add_option("--imu-topic", options.bag.imu_topic, "bags: the Imu topic (default: the only one)");
  command->add_option("--base-frame", options.bag.base_frame, "bags: the robot's frame (default: the odometry's child frame)");
  command->add_option("--odom-frame", options.bag.odom_frame, "bags: the odometry frame (default: the odometry's frame)");
  command->add_option("--scan-odometry", options.bag.scan_odometry,
                      "bags: each scan's odometry pose: interpolated at its stamp, or the latest reading recorded before "
                      "it (as CARMEN's logger wrote FLASER; for logs whose stamps are wrong)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, OdometryAtScan>{{"interpolated", OdometryAtScan::kInterpolated},
                                                                               {"latest", OdometryAtScan::kLatest}}))
      ->default_str("interpolated");
}

std::vector<std::string> reader_warnings(const LogReader& reader) {
  return reader.carmen() != nullptr ? reader_warnings(*reader.carmen()) : reader.bag()->warnings();
}

void print_reader_warnings(const LogReader& reader) {
  for (const std::string& warning : reader_warnings(reader)) std::fprintf(stderr, "%s\n", warning.c_str());
}

void add_odometry_time_offset_option(CLI::App* command, std::string& spec) {
  command->add_option("--odometry-time-offset", spec,
                      "s the odometry runs ahead of the laser (negative: behind): auto (estimated from the turns the scans "
                      "show, compensated when confident and at least 0.25 s), off, or a number of seconds in [-10, 10] "
                      "(docs/time_offset.md)")
      ->check([](const std::string& text) -> std::string {
        double value = 0.0;
        if (text == "auto" || text == "off") return {};
        if (CLI::detail::lexical_cast(text, value) && std::isfinite(value) && std::abs(value) <= 10.0) return {};
        return "must be auto, off or seconds in [-10, 10], got " + text;
      })
      ->capture_default_str();
}

// The log as the time-offset estimate needs it, read twice: first every message's stamp and
// odometry pose (all the estimate reads of most scans), then again for the scans it matches
// (odometry_time_offset_scans: at most 6,000 of them). Holding a whole long log instead (an hour
// of a 1080-beam scanner at 40 Hz is over a gigabyte; ten passes of Intel as messages, 130 MB)
// would be the run's peak memory.
namespace {

TimeOffsetInput read_for_time_offset(const std::string& log, const LogReaderOptions& options, Progress& progress) {
  TimeOffsetInput input;
  std::size_t count = 0;
  {
    LogReader reader(log, options);
    while (auto message = reader.next()) {
      input.add(*message, /*with_scan=*/false);
      if (++count % 4096 == 0) progress.update(0.5 * reader.progress(), fmt::format("{} messages read", count));
    }
  }
  const std::vector<std::size_t> used = odometry_time_offset_scans(input);
  LogReader reader(log, options);
  std::size_t index = 0;
  for (const std::size_t wanted : used) {
    std::optional<SensorMessage> message;
    while (index <= wanted) {
      message = reader.next();
      check(message.has_value(), log + ": the log changed while it was read for the odometry time offset");
      ++index;
    }
    auto* laser = std::get_if<LaserMessage>(&*message);
    check(laser != nullptr && input.set_scan(wanted, std::move(laser->scan)),
          log + ": the log changed while it was read for the odometry time offset");
    if (index % 256 == 0) progress.update(0.5 + 0.5 * reader.progress(), fmt::format("{} scans read again", used.size()));
  }
  return input;
}

// --odometry-time-offset auto: the estimate, applied when significant.
OdometryTimeOffsetChoice auto_choice(const OdometryTimeOffset& estimate) {
  OdometryTimeOffsetChoice choice{.mode = "auto", .estimate = estimate};
  if (estimate.significant) choice.applied = estimate.offset;
  return choice;
}

}  // namespace

OdometryTimeOffsetChoice estimate_odometry_time_offset_choice(const std::vector<SensorMessage>& messages) {
  return auto_choice(estimate_odometry_time_offset(messages));
}

OdometryTimeOffsetChoice resolve_odometry_time_offset(const std::string& log, const std::string& spec,
                                                      LogReaderOptions& options, bool quiet) {
  OdometryTimeOffsetChoice choice;
  if (spec == "auto") {
    LogReaderOptions as_logged = options;
    as_logged.odometry_time_offset = 0.0;
    Progress progress("odometry time offset", quiet);
    choice = auto_choice(estimate_odometry_time_offset(read_for_time_offset(log, as_logged, progress)));
    progress.finish();
  } else if (spec != "off") {
    choice.mode = "given";
    check(CLI::detail::lexical_cast(spec, choice.applied) && std::isfinite(choice.applied),
          "--odometry-time-offset: not auto, off or a number: " + spec);
  }
  options.odometry_time_offset = choice.applied;
  return choice;
}

JsonObject odometry_time_offset_json(const OdometryTimeOffsetChoice& choice) {
  JsonObject json;
  json.add("odometry_time_offset_s", choice.applied).add("odometry_time_offset_applied", choice.applied != 0.0);
  json.add("odometry_time_offset_mode", choice.mode);
  if (!choice.estimate) return json;
  const OdometryTimeOffset& estimate = *choice.estimate;
  json.add("odometry_time_offset_estimated", estimate.estimated);
  json.add("odometry_time_offset_estimate_s", estimate.estimated ? std::optional<double>(estimate.offset) : std::nullopt);
  json.add("odometry_time_offset_best_s", estimate.best);
  json.add("odometry_time_offset_uncertainty_s",
           std::isfinite(estimate.uncertainty) ? std::optional<double>(estimate.uncertainty) : std::nullopt);
  json.add("odometry_time_offset_pairs", estimate.pairs).add("odometry_time_offset_turning_pairs", estimate.turning_pairs);
  json.add("odometry_time_offset_reason", estimate.reason).add("odometry_time_offset_wall_s", estimate.seconds);
  return json;
}

}  // namespace slam2d::cli
