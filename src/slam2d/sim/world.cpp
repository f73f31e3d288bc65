// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "slam2d/core/error.hpp"
#include "slam2d/sim/hospital_world.hpp"
#include "slam2d/sim/office_world.hpp"
#include "slam2d/sim/ray_caster.hpp"

namespace slam2d {

namespace {

constexpr double kMaxMapCells = 1e8;  // a bound on the map's memory

/// The part of the wall inside the box (Liang & Barsky clipping), or nullopt.
std::optional<WallSegment> clip_segment(const WallSegment& wall, const Eigen::AlignedBox2d& box) {
  const Eigen::Vector2d d = wall.b - wall.a;
  double s0 = 0.0, s1 = 1.0;
  for (int axis = 0; axis < 2; ++axis) {
    if (d[axis] == 0.0) {
      if (wall.a[axis] < box.min()[axis] || wall.a[axis] > box.max()[axis]) return std::nullopt;
      continue;
    }
    double lo = (box.min()[axis] - wall.a[axis]) / d[axis], hi = (box.max()[axis] - wall.a[axis]) / d[axis];
    if (lo > hi) std::swap(lo, hi);
    s0 = std::max(s0, lo);
    s1 = std::min(s1, hi);
  }
  if (s0 > s1) return std::nullopt;
  return WallSegment{wall.a + s0 * d, wall.a + s1 * d};
}

/// Marks the cells along the wall, sampled every resolution / 4: every cell it crosses except, at
/// most, one that it only clips at a corner.
void mark_segment(OccupancyMap& map, const WallSegment& wall) {
  const double length = (wall.b - wall.a).norm();
  const int samples = static_cast<int>(std::ceil(4.0 * length / map.resolution)) + 1;
  for (int i = 0; i <= samples; ++i) {
    const Eigen::Vector2d p = wall.a + (wall.b - wall.a) * (static_cast<double>(i) / samples);
    const Eigen::Vector2i cell = map.cell_of(p);
    if (map.contains(cell.x(), cell.y())) map.at(cell.x(), cell.y()) = OccupancyMap::kOccupied;
  }
}

}  // namespace

std::vector<std::string> world_names() { return {"office", "hospital"}; }

World make_world(const std::string& name) {
  if (name == "office") return make_office_world();
  if (name == "hospital") return make_hospital_world();
  std::string known;
  for (const std::string& n : world_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown world '" + name + "' (known worlds: " + known + ")");
}

std::optional<double> cast_ray(const World& world, const Eigen::Vector2d& origin, double angle, double max_range) {
  const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
  double best = std::numeric_limits<double>::infinity();
  for (const WallSegment& wall : world.walls) {
    if (const auto t = intersect_ray_segment(origin, direction, wall)) best = std::min(best, *t);
  }
  if (best <= max_range) return best;
  return std::nullopt;
}

double distance_to_segment(const Eigen::Vector2d& point, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double length_squared = ab.squaredNorm();
  if (length_squared == 0.0) return (point - a).norm();
  const double s = std::clamp((point - a).dot(ab) / length_squared, 0.0, 1.0);
  return (point - (a + s * ab)).norm();
}

double distance_to_nearest_wall(const World& world, const Eigen::Vector2d& point) {
  double best = std::numeric_limits<double>::infinity();
  for (const WallSegment& wall : world.walls) best = std::min(best, distance_to_segment(point, wall.a, wall.b));
  return best;
}

OccupancyMap rasterize_world(const World& world, double resolution) {
  check(std::isfinite(resolution) && resolution > 0.0, "rasterize_world: resolution must be positive");
  check(!world.bounds.isEmpty() && world.bounds.min().allFinite() && world.bounds.max().allFinite(),
        "rasterize_world: the world's bounds must be finite and not empty");
  const Eigen::Vector2d cells = world.bounds.sizes() / resolution + Eigen::Vector2d::Constant(3.0);
  check(cells.x() * cells.y() <= kMaxMapCells, "rasterize_world: the map would have too many cells");
  OccupancyMap map;
  map.resolution = resolution;
  map.origin = SE2(world.bounds.min() - Eigen::Vector2d::Constant(resolution), 0.0);
  const Eigen::Vector2d size = world.bounds.sizes() + Eigen::Vector2d::Constant(2.0 * resolution);
  map.width = static_cast<int>(std::ceil(size.x() / resolution));
  map.height = static_cast<int>(std::ceil(size.y() / resolution));
  map.cells.assign(static_cast<std::size_t>(map.width) * map.height, OccupancyMap::kFree);
  const Eigen::AlignedBox2d box(map.origin.translation(), map.origin.translation() + size);
  for (const WallSegment& wall : world.walls) {
    check(wall.a.allFinite() && wall.b.allFinite(), "rasterize_world: walls must be finite");
    if (const auto clipped = clip_segment(wall, box)) mark_segment(map, *clipped);
  }
  return map;
}

}  // namespace slam2d
