// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The reader options shared by every command that reads a log (info, map, localize, odometry,
// match, match-bench, convert): the sensor-geometry overrides --fov, --angle-min, --angle-increment in
// degrees and --range-max in metres on the command line, radians and metres in CarmenReaderOptions,
// which beat the log's PARAM lines and the CARMEN convention (docs/sensor_geometry.md); and
// --raw-odometry, which turns off the repair of odometry that integrates reversing as forward
// driving (docs/odometry_guard.md). Also what the reader decided, for the summaries.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "slam2d/io/carmen.hpp"
#include "slam2d/io/log_reader.hpp"

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

}  // namespace slam2d::cli
