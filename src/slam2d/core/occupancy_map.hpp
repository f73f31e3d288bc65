// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// OccupancyMap: a finished map as a plain value, in the convention of ROS's nav_msgs/OccupancyGrid.
// Cells are row-major with row 0 at the bottom (smallest y); `origin` is the pose of the
// lower-left corner of cell (0, 0) in the map frame.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OccupancyMap {
  static constexpr std::int8_t kUnknown = -1;
  static constexpr std::int8_t kFree = 0;
  static constexpr std::int8_t kOccupied = 100;

  double resolution = 0.05;  // m per cell
  SE2 origin;                // pose of the lower-left corner of cell (0, 0)
  int width = 0;             // cells along x
  int height = 0;            // cells along y
  std::vector<std::int8_t> cells;  // width * height; -1 unknown, else occupancy 0..100 (%)

  std::int8_t at(int ix, int iy) const { return cells[static_cast<std::size_t>(iy) * width + ix]; }
  std::int8_t& at(int ix, int iy) { return cells[static_cast<std::size_t>(iy) * width + ix]; }
  bool contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width && iy < height; }
  /// Centre of a cell in the map frame.
  Eigen::Vector2d cell_center(int ix, int iy) const;
  /// The cell that holds a map-frame point (may lie outside the map: check with contains()).
  Eigen::Vector2i cell_of(const Eigen::Vector2d& point) const;

  bool operator==(const OccupancyMap& other) const = default;
};

/// The centres of the cells whose occupancy is at least `threshold` (%), in the map frame.
PointCloud2 occupied_points(const OccupancyMap& map, int threshold);

/// One map over both: `above`'s known cells, `below`'s where `above` knows nothing. Both of one
/// resolution, axis-aligned, their origins on one lattice of cells (two grids of one geometry);
/// an empty map leaves the other.
OccupancyMap overlay(const OccupancyMap& below, const OccupancyMap& above);

/// An 8-bit RGB raster, row-major with row 0 at the top, as image files store it.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // 3 * width * height

  RgbImage() = default;
  RgbImage(int w, int h, std::uint8_t fill = 0)
      : width(w), height(h), rgb(static_cast<std::size_t>(3) * w * h, fill) {}
  void set(int col, int row, std::uint8_t r, std::uint8_t g, std::uint8_t b);
  bool operator==(const RgbImage& other) const = default;
};

}  // namespace slam2d
