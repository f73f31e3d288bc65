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

PointCloud2 occupied_points(const OccupancyMap& map, int threshold) {
  PointCloud2 cloud;
  for (int iy = 0; iy < map.height; ++iy) {
    for (int ix = 0; ix < map.width; ++ix) {
      if (map.at(ix, iy) >= threshold) cloud.points.push_back(map.cell_center(ix, iy));
    }
  }
  return cloud;
}

OccupancyMap overlay(const OccupancyMap& below, const OccupancyMap& above) {
  if (below.cells.empty()) return above;
  if (above.cells.empty()) return below;
  // Each map's cell (0, 0) in whole cells from `below`'s.
  const auto offset = [&](const OccupancyMap& map) {
    const Eigen::Vector2d d = (map.origin.translation() - below.origin.translation()) / below.resolution;
    return Eigen::Vector2i(static_cast<int>(std::lround(d.x())), static_cast<int>(std::lround(d.y())));
  };
  const Eigen::Vector2i a = offset(above);
  const Eigen::Vector2i first = a.cwiseMin(Eigen::Vector2i::Zero());
  const Eigen::Vector2i last = (a + Eigen::Vector2i(above.width, above.height)).cwiseMax(Eigen::Vector2i(below.width, below.height));
  OccupancyMap map;
  map.resolution = below.resolution;
  map.origin = SE2(below.origin.x() + first.x() * below.resolution, below.origin.y() + first.y() * below.resolution, 0.0);
  map.width = last.x() - first.x();
  map.height = last.y() - first.y();
  map.cells.assign(static_cast<std::size_t>(map.width) * map.height, OccupancyMap::kUnknown);
  for (int iy = 0; iy < below.height; ++iy) {
    for (int ix = 0; ix < below.width; ++ix) map.at(ix - first.x(), iy - first.y()) = below.at(ix, iy);
  }
  for (int iy = 0; iy < above.height; ++iy) {
    for (int ix = 0; ix < above.width; ++ix) {
      if (above.at(ix, iy) != OccupancyMap::kUnknown) map.at(ix + a.x() - first.x(), iy + a.y() - first.y()) = above.at(ix, iy);
    }
  }
  return map;
}

}  // namespace slam2d
