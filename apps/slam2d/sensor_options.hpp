// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The reader options shared by every command that reads a log (info, map, localize, odometry,
// match, match-bench, convert): the sensor-geometry overrides --fov, --angle-min, --angle-increment in
// degrees and --range-max in metres on the command line, radians and metres in CarmenReaderOptions,
// which beat the log's PARAM lines and the CARMEN convention (docs/sensor_geometry.md); and
// --raw-odometry, which turns off the repair of odometry that integrates reversing as forward
// driving (docs/odometry_guard.md). Also what the reader decided, for the summaries; and
// --odometry-time-offset (map, odometry): the odometry's time offset against the laser, estimated
// or given, which the reader then compensates (docs/time_offset.md).

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

#include "json.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/registration/odometry_time_offset.hpp"

namespace slam2d::cli {

/// Adds --fov DEG, --angle-min DEG, --angle-increment DEG, --range-max M and --raw-odometry to `command`, writing
/// into `options` (which must outlive the parse). Each value is checked when parsed: the field of
/// view in (0, 360], the increment and the range positive, all finite. `range_max_help` replaces
/// the help of --range-max where the command gives it a further meaning.
void add_sensor_options(CLI::App* command, CarmenReaderOptions& options, const std::string& range_max_help = "");

/// The same, and the bag options --scan-topic, --odom-topic, --imu-topic, --base-frame and
/// --odom-frame (automatic when the bag has one candidate) for a command that reads any log.
void add_sensor_options(CLI::App* command, LogReaderOptions& options, const std::string& range_max_help = "");

/// The warnings of what `reader` decided, one line each: the FLASER/RLASER geometries (PARAM lines
/// dropped, ambiguous units: "PATH:LINE: warning: FLASER geometry, N beams: ...") and the odometry
/// steps it repaired for reversing ("PATH: warning: the odometry integrates reversing as forward
/// driving: ..."). Call it after reading.
std::vector<std::string> reader_warnings(const CarmenReader& reader);

/// The same on stderr.
void print_reader_warnings(const CarmenReader& reader);
/// The warnings of any log: CARMEN's above, or what the bag assembly could not decide.
std::vector<std::string> reader_warnings(const LogReader& reader);
void print_reader_warnings(const LogReader& reader);

/// What --odometry-time-offset auto|off|SECONDS decided (registration/odometry_time_offset.hpp).
struct OdometryTimeOffsetChoice {
  std::string mode = "off";                    // auto | off | given
  std::optional<OdometryTimeOffset> estimate;  // auto: the estimate
  double applied = 0.0;                        // s, the LogReaderOptions::odometry_time_offset set
};

/// Adds --odometry-time-offset (default auto) to `command`, writing the text into `spec`.
void add_odometry_time_offset_option(CLI::App* command, std::string& spec);

/// Resolves `spec` for `log`: off; SECONDS, applied as given; auto, the log read once and the
/// offset estimated, applied when confident and significant. Sets options.odometry_time_offset.
OdometryTimeOffsetChoice resolve_odometry_time_offset(const std::string& log, const std::string& spec,
                                                      LogReaderOptions& options, bool quiet);

/// The estimate of a log's messages, as auto would decide (for `slam2d info`).
OdometryTimeOffsetChoice estimate_odometry_time_offset_choice(const std::vector<SensorMessage>& messages);

/// The summary keys: odometry_time_offset_s (applied, 0 when none), _applied, _mode, and for auto
/// _estimated, _estimate_s, _uncertainty_s, _reason and _wall_s.
JsonObject odometry_time_offset_json(const OdometryTimeOffsetChoice& choice);

}  // namespace slam2d::cli
