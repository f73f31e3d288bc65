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

}  // namespace slam2d
