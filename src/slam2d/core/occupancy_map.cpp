// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/occupancy_map.hpp"

#include <cmath>

namespace slam2d {

Eigen::Vector2d OccupancyMap::cell_center(int ix, int iy) const {
  return origin.act(Eigen::Vector2d((ix + 0.5) * resolution, (iy + 0.5) * resolution));
}

Eigen::Vector2i OccupancyMap::cell_of(const Eigen::Vector2d& point) const {
  const Eigen::Vector2d local = origin.inverse().act(point) / resolution;
  return {static_cast<int>(std::floor(local.x())), static_cast<int>(std::floor(local.y()))};
}

void RgbImage::set(int col, int row, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  if (col < 0 || row < 0 || col >= width || row >= height) return;
  const std::size_t i = 3 * (static_cast<std::size_t>(row) * width + col);
  rgb[i] = r;
  rgb[i + 1] = g;
  rgb[i + 2] = b;
}

}  // namespace slam2d
