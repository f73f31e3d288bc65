// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Simulated 2D worlds: walls as line segments in the map frame, plus a route the robot drives.
// Ray casting here is the brute-force reference; RayCaster (ray_caster.hpp) is the fast path.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slam2d/core/occupancy_map.hpp"

namespace slam2d {

/// A wall: the line segment from a to b (m, map frame). Walls have no thickness.
struct WallSegment {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
};

struct World {
  std::string name;
  std::vector<WallSegment> walls;
  Eigen::AlignedBox2d bounds;  // m, the box that holds every wall
  /// Waypoints (m) of a loop-closing tour. The route is closed: after the last waypoint the
  /// robot drives back to the first. The robot starts at route[0] facing route[1].
  std::vector<Eigen::Vector2d> route;
};

/// The names make_world knows.
std::vector<std::string> world_names();

/// A built-in world by name: "office" (a 30 m x 20 m office floor, see office_world.cpp) or
/// "hospital" (an 80 m x 30 m corridor ring, see hospital_world.cpp).
/// Throws Error naming the known worlds for an unknown name.
World make_world(const std::string& name);

/// Distance (m) along the ray from `origin` at bearing `angle` (rad, map frame) to the first
/// wall, or nullopt when no wall is hit within `max_range` (m). Brute force over all walls.
std::optional<double> cast_ray(const World& world, const Eigen::Vector2d& origin, double angle, double max_range);

/// Distance (m) of a point to the nearest wall (infinity for a world without walls).
double distance_to_nearest_wall(const World& world, const Eigen::Vector2d& point);

/// Distance (m) from a point to the segment [a, b].
double distance_to_segment(const Eigen::Vector2d& point, const Eigen::Vector2d& a, const Eigen::Vector2d& b);

/// The world as a ground-truth occupancy map covering `bounds` plus one cell: cells a wall passes
/// through are occupied (100), all others free (0). `resolution` in m per cell (> 0).
OccupancyMap rasterize_world(const World& world, double resolution);

}  // namespace slam2d
