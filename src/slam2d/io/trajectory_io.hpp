// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Trajectory files.
// - slam2d text (default): "timestamp x y theta" per line (s, m, m, rad), '#' comments.
// - TUM: "timestamp tx ty tz qx qy qz qw" per line, z = 0, rotation about z.
// Readers keep file order (stamps may go backwards) and reject non-finite values with
// ParseError("PATH:LINE: ..."). Writers are atomic and use the shortest exact number form.

#include <string>

#include "slam2d/core/trajectory.hpp"

namespace slam2d {

Trajectory read_trajectory(const std::string& path);
void write_trajectory(const std::string& path, const Trajectory& trajectory);

Trajectory read_trajectory_tum(const std::string& path);
void write_trajectory_tum(const std::string& path, const Trajectory& trajectory);

enum class TrajectoryFormat { kText, kTum };
/// "text" | "tum" (Error otherwise), for --format.
TrajectoryFormat trajectory_format_from_name(const std::string& name);
/// The format of a trajectory file by its first data line: 4 numbers are slam2d text, 8 are TUM
/// (what evo reads and writes). ParseError("PATH:LINE: ...") for another count.
TrajectoryFormat detect_trajectory_format(const std::string& path);
/// Reads either format (detect_trajectory_format) / writes the one asked for.
Trajectory read_any_trajectory(const std::string& path);
void write_trajectory(const std::string& path, const Trajectory& trajectory, TrajectoryFormat format);

}  // namespace slam2d
