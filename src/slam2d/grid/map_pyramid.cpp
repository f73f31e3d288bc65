// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/map_pyramid.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "slam2d/core/error.hpp"

namespace slam2d {

MapPyramid::MapPyramid(const MapPyramidConfig& config) : config_(config) {
  check_fields(config, "MapPyramidConfig");
  grids_.reserve(static_cast<std::size_t>(config.levels));
  for (int k = 0; k < config.levels; ++k) {
    OccupancyGridConfig grid = config.grid;
    grid.resolution = std::ldexp(config.grid.resolution, k);  // r 2^k, exact
    grids_.emplace_back(grid);
  }
}

void MapPyramid::integrate_scan(const LaserScan& scan, const SE2& T_map_robot) {
  // The surface steps do not depend on the resolution: found once, on the finest level.
  std::vector<OccupancyGrid::SurfaceStep> steps;
  if (config_.grid.surface_hit_weight > 0.0 && T_map_robot.vector().allFinite()) {
    steps = grids_.front().surface_steps(scan, T_map_robot * scan.T_robot_sensor);
  }
  for (OccupancyGrid& grid : grids_) grid.integrate_scan(scan, T_map_robot, steps);
}

const OccupancyGrid& MapPyramid::level(int k) const {
  check(k >= 0 && k < levels(), "MapPyramid::level: no level " + std::to_string(k));
  return grids_[static_cast<std::size_t>(k)];
}

std::size_t MapPyramid::memory_bytes() const {
  std::size_t bytes = sizeof(*this);
  for (const OccupancyGrid& grid : grids_) bytes += grid.memory_bytes();
  return bytes;
}

}  // namespace slam2d
