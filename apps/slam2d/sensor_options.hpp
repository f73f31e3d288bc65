#pragma once
// The sensor-geometry overrides shared by every command that reads a CARMEN log (info, map,
// localize, odometry, match-bench): --fov, --angle-min, --angle-increment in degrees and
// --range-max in metres on the command line, radians and metres in CarmenReaderOptions. They beat
// the log's PARAM lines and the CARMEN convention (docs/sensor_geometry.md).

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "slam2d/io/carmen.hpp"

namespace slam2d::cli {

/// Adds --fov DEG, --angle-min DEG, --angle-increment DEG and --range-max M to `command`, writing
/// into `options` (which must outlive the parse). Each value is checked when parsed: the field of
/// view in (0, 360], the increment and the range positive, all finite. `range_max_help` replaces
/// the help of --range-max where the command gives it a further meaning.
void add_sensor_options(CLI::App* command, CarmenReaderOptions& options, const std::string& range_max_help = "");

/// The warnings of the FLASER/RLASER geometries `reader` decided (PARAM lines dropped, ambiguous
/// units), one line each: "PATH:LINE: warning: FLASER geometry, N beams: ...". Call it after reading.
std::vector<std::string> geometry_warnings(const CarmenReader& reader);

/// The same on stderr.
void print_geometry_warnings(const CarmenReader& reader);

}  // namespace slam2d::cli
