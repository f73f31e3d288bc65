// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/bilinear.hpp"

#include <cmath>

namespace slam2d {

namespace {

double cell_probability(const OccupancyCell& cell) {
  return cell.last_scan == 0 ? 0.5 : occupancy_probability(cell.log_odds);
}

}  // namespace

// P(occupied) in single precision (expf is several times faster than exp; the cells hold float
// log-odds anyway): within 1e-7 of probability_from_log_odds.
double occupancy_probability(float log_odds) { return static_cast<double>(1.0f / (1.0f + std::exp(-log_odds))); }

OccupancyInterpolator::OccupancyInterpolator(const OccupancyGrid& grid)
    : corners_(grid), geometry_(grid.geometry()) {
  thread_local Memo memo(occupancy_probability);
  memo_ = &memo;
}

BilinearCorner bilinear_corner(const GridGeometry& geometry, const Eigen::Vector2d& point) {
  // Continuous index of the point with the samples (cell centres) at integer positions.
  const double u = (point.x() - geometry.origin.x()) / geometry.resolution - 0.5;
  const double v = (point.y() - geometry.origin.y()) / geometry.resolution - 0.5;
  const int i = GridGeometry::floor_to_int(u);
  const int j = GridGeometry::floor_to_int(v);
  return {CellIndex{i, j}, Eigen::Vector2d(u - i, v - j)};
}

BilinearSample interpolate_occupancy(const OccupancyGrid& grid, const Eigen::Vector2d& point) {
  const GridGeometry& geometry = grid.geometry();
  if (!geometry.in_index_range(point, GridGeometry::kMaxCellIndex - 2.0)) return {0.5, Eigen::Vector2d::Zero()};
  const BilinearCorner c = bilinear_corner(geometry, point);
  const std::array<double, 4> m = occupancy_corners(grid, c.cell, cell_probability);
  return bilinear_blend(m[0], m[1], m[2], m[3], c.fraction, geometry.resolution);
}

}  // namespace slam2d
