// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// --mcap OUT.mcap of `map` and `localize`: the run for Foxglove (io/run_mcap.hpp), its scans read
// again from the log.

#include <string>

#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/io/log_reader.hpp"

namespace slam2d::cli {

/// Reads `log` again and writes at `path` each laser scan (front lasers only when `front_only`, as
/// localize uses them) with the pose of `trajectory` (the robot's, one per such scan, in order),
/// then the map and the path. Throws Error when the log's scans and the trajectory do not pair up.
void write_run_mcap(const std::string& path, const std::string& log, const LogReaderOptions& input, bool front_only,
                    const OccupancyMap& map, const Trajectory& trajectory);

}  // namespace slam2d::cli
