// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Cell indexing shared by every grid of the project.
//
// A grid with resolution r and origin o splits the plane into square cells; cell (x, y) covers
// [o.x + x r, o.x + (x + 1) r) x [o.y + y r, o.y + (y + 1) r). A point falls in the cell
// floor((p - o) / r); the cell's centre is o + (i + 1/2) r. Cell indices are plain ints and may be
// negative: the grids grow in every direction.

#include <Eigen/Core>
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstddef>
#include <functional>

namespace slam2d {

struct CellIndex {
  int x = 0;
  int y = 0;

  friend bool operator==(const CellIndex&, const CellIndex&) = default;
  friend CellIndex operator+(CellIndex a, CellIndex b) { return {a.x + b.x, a.y + b.y}; }
  friend CellIndex operator-(CellIndex a, CellIndex b) { return {a.x - b.x, a.y - b.y}; }
};

/// An axis-aligned, inclusive range of cells [min, max]. Default-constructed boxes are empty.
struct CellBox {
  CellIndex min{INT_MAX, INT_MAX};
  CellIndex max{INT_MIN, INT_MIN};

  bool empty() const { return min.x > max.x || min.y > max.y; }
  int width() const { return empty() ? 0 : max.x - min.x + 1; }
  int height() const { return empty() ? 0 : max.y - min.y + 1; }
  bool contains(CellIndex cell) const {
    return cell.x >= min.x && cell.x <= max.x && cell.y >= min.y && cell.y <= max.y;
  }
  /// Grows the box to hold `cell`.
  void extend(CellIndex cell) {
    min = {std::min(min.x, cell.x), std::min(min.y, cell.y)};
    max = {std::max(max.x, cell.x), std::max(max.y, cell.y)};
  }
  void extend(const CellBox& other) {
    if (other.empty()) return;
    extend(other.min);
    extend(other.max);
  }
  friend bool operator==(const CellBox&, const CellBox&) = default;
};

/// Resolution and origin of a grid: converts between map-frame points and cells.
struct GridGeometry {
  double resolution = 0.05;                          // m per cell
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // m, lower-left corner of cell (0, 0)

  /// The cell holding `point`: floor((point - origin) / resolution). The point must be finite and
  /// within INT_MAX cells of the origin (callers check with in_index_range()).
  CellIndex cell_of(const Eigen::Vector2d& point) const {
    return {floor_to_int((point.x() - origin.x()) / resolution), floor_to_int((point.y() - origin.y()) / resolution)};
  }
  /// floor(value) as an int, for finite |value| < 2^31 (faster than std::floor without SSE4.1).
  static int floor_to_int(double value) {
    const int truncated = static_cast<int>(value);
    return truncated - static_cast<int>(value < truncated);
  }
  /// The centre of a cell, in metres.
  Eigen::Vector2d cell_center(CellIndex cell) const {
    return origin + resolution * Eigen::Vector2d(cell.x + 0.5, cell.y + 0.5);
  }
  /// The lower-left corner of a cell, in metres.
  Eigen::Vector2d cell_corner(CellIndex cell) const {
    return origin + resolution * Eigen::Vector2d(cell.x, cell.y);
  }
  /// True when `point` is finite and its cell index is at most `limit` cells from the origin.
  bool in_index_range(const Eigen::Vector2d& point, double limit = kMaxCellIndex) const {
    const Eigen::Vector2d scaled = (point - origin) / resolution;
    return std::abs(scaled.x()) <= limit && std::abs(scaled.y()) <= limit;  // false for NaN
  }

  /// Largest |cell index| the grids accept: far beyond any map, far below int overflow.
  static constexpr double kMaxCellIndex = 1 << 28;
};

struct CellIndexHash {
  std::size_t operator()(CellIndex cell) const {
    return std::hash<long long>()((static_cast<long long>(cell.x) << 32) ^ static_cast<unsigned>(cell.y));
  }
};

}  // namespace slam2d
