// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Bilinear interpolation of a grid map and of its gradient at continuous coordinates:
// S. Kohlbrecher, O. von Stryk, J. Meyer, U. Klingauf, "A flexible and scalable SLAM system with
// full 3D motion estimation", SSRR 2011, Sec. IV-A, Eq. (4)-(6).
//
// The samples sit at the cell centres. A point P lies in the square of the four centres
// P00 = centre(i, j), P11 = centre(i + 1, j + 1) around it; with the fractions
// fx = (x - x0) / r, fy = (y - y0) / r in [0, 1):
//   M(P)     = (1 - fy) ((1 - fx) M00 + fx M10) + fy ((1 - fx) M01 + fx M11)        Eq. (4)
//   dM/dx(P) = ((1 - fy) (M10 - M00) + fy (M11 - M01)) / r                             Eq. (5)
//   dM/dy(P) = ((1 - fx) (M01 - M00) + fx (M11 - M10)) / r                             Eq. (6)
// M is exact at the cell centres and continuous everywhere; the gradient is the derivative of M
// inside each square (it jumps across the lines joining cell centres, as in the paper).

#include <Eigen/Core>
#include <array>
#include <bit>
#include <climits>
#include <cstdint>
#include <cmath>

#include "slam2d/grid/grid_geometry.hpp"
#include "slam2d/grid/occupancy_grid.hpp"

namespace slam2d {

struct BilinearSample {
  double value = 0.0;                                  // M(P), the interpolated cell value
  Eigen::Vector2d gradient = Eigen::Vector2d::Zero();  // (dM/dx, dM/dy), per metre, map frame
};

/// The base cell (i, j) of the interpolation square around `point` and the fractions (fx, fy).
struct BilinearCorner {
  CellIndex cell;
  Eigen::Vector2d fraction = Eigen::Vector2d::Zero();  // in [0, 1)
};
BilinearCorner bilinear_corner(const GridGeometry& geometry, const Eigen::Vector2d& point);

/// Eq. (4) alone: the value at fractions (fx, fy) of the square from the four corner values
/// m00 = M(i, j), m10 = M(i + 1, j), m01 = M(i, j + 1), m11 = M(i + 1, j + 1).
inline double bilinear_value(double m00, double m10, double m01, double m11, double fx, double fy) {
  return (1.0 - fy) * ((1.0 - fx) * m00 + fx * m10) + fy * ((1.0 - fx) * m01 + fx * m11);
}

/// Eq. (4)-(6) from the four corner values (bilinear_value's) and the fractions.
inline BilinearSample bilinear_blend(double m00, double m10, double m01, double m11,
                                     const Eigen::Vector2d& fraction, double resolution) {
  const double fx = fraction.x();
  const double fy = fraction.y();
  BilinearSample sample;
  sample.value = bilinear_value(m00, m10, m01, m11, fx, fy);                                     // Eq. (4)
  sample.gradient.x() = ((1.0 - fy) * (m10 - m00) + fy * (m11 - m01)) / resolution;                // Eq. (5)
  sample.gradient.y() = ((1.0 - fx) * (m01 - m00) + fx * (m11 - m10)) / resolution;                // Eq. (6)
  return sample;
}

/// Eq. (4)-(6) over any cell value: value_of(CellIndex) -> double. `point` must be finite and
/// within GridGeometry::kMaxCellIndex cells of the origin.
template <typename ValueOf>
BilinearSample interpolate_bilinear(const GridGeometry& geometry, ValueOf&& value_of, const Eigen::Vector2d& point) {
  const BilinearCorner c = bilinear_corner(geometry, point);
  const CellIndex i = c.cell;
  return bilinear_blend(value_of(i), value_of(CellIndex{i.x + 1, i.y}), value_of(CellIndex{i.x, i.y + 1}),
                        value_of(CellIndex{i.x + 1, i.y + 1}), c.fraction, geometry.resolution);
}

/// The corners of occupancy_corners for many reads of one grid that does not change meanwhile,
/// the last tile looked up remembered.
class CornerReader {
 public:
  explicit CornerReader(const OccupancyGrid& grid) : cells_(grid.cells()) {}
  /// The four corners m00, m10, m01, m11 of the cells i, i + x, i + y, i + x + y, each
  /// probability(cell), 0.5 where no tile is allocated.
  template <typename Probability>
  std::array<double, 4> operator()(CellIndex i, Probability&& probability) {
    constexpr int kMask = CellGrid::kTileSize - 1;
    if ((i.x & kMask) != kMask && (i.y & kMask) != kMask) {  // all four in one tile
      const CellGrid::Tile* t = tile(CellGrid::tile_of(i));
      if (t == nullptr) return {0.5, 0.5, 0.5, 0.5};
      const int offset = CellGrid::offset_in_tile(i);
      return {probability(t->cells[offset]), probability(t->cells[offset + 1]),
              probability(t->cells[offset + CellGrid::kTileSize]),
              probability(t->cells[offset + CellGrid::kTileSize + 1])};
    }
    return {probability(cells_.at(i)), probability(cells_.at({i.x + 1, i.y})), probability(cells_.at({i.x, i.y + 1})),
            probability(cells_.at({i.x + 1, i.y + 1}))};
  }

 private:
  using CellGrid = TiledGrid<OccupancyCell>;
  const CellGrid::Tile* tile(CellIndex index) {
    if (index != tile_index_) {
      tile_ = cells_.find_tile(index);
      tile_index_ = index;
    }
    return tile_;
  }

  const CellGrid& cells_;
  CellIndex tile_index_{INT_MIN, INT_MIN};  // no tile has this index (|tile index| < 2^23)
  const CellGrid::Tile* tile_ = nullptr;
};

/// The corner values m00, m10, m01, m11 of the interpolation square with base cell i of an
/// occupancy grid, each cell read as probability_of(const OccupancyCell&). The four cells are read
/// from one tile when they share it (63 squares in 64 along each axis); a missing tile reads 0.5.
template <typename ProbabilityOf>
std::array<double, 4> occupancy_corners(const OccupancyGrid& grid, CellIndex i, ProbabilityOf&& probability_of) {
  return CornerReader(grid)(i, probability_of);
}

/// Eq. (4)-(6) over the occupancy probability of a grid (0.5 in unknown cells): Hector's map
/// value M. A point that is not finite or lies beyond the index range reads 0.5, gradient 0.
BilinearSample interpolate_occupancy(const OccupancyGrid& grid, const Eigen::Vector2d& point);

/// P(occupied) = 1 / (1 + exp(-l)) of a cell's log-odds in single precision, as
/// interpolate_occupancy reads it.
double occupancy_probability(float log_odds);

/// A memo of a function of a float, f(l), exact: each slot holds a key and f(key), computed by f
/// itself, so a hit returns bit for bit what f would return (a cache, not an approximation).
/// Direct-mapped on the float's bits. One per thread (not safe to share between threads).
template <int kLog2Slots>
class FloatMemo {
 public:
  template <typename F>
  explicit FloatMemo(F&& f) {
    keys_.fill(0u);  // +0.0f
    values_.fill(f(0.0f));
  }
  template <typename F>
  double operator()(float l, F&& f) {
    const auto bits = std::bit_cast<std::uint32_t>(l);
    const std::uint32_t slot = (bits * 0x9E3779B1u) >> (32 - kLog2Slots);
    if (keys_[slot] == bits) return values_[slot];
    const double value = f(l);
    keys_[slot] = bits;
    values_[slot] = value;
    return value;
  }

 private:
  std::array<std::uint32_t, (1 << kLog2Slots)> keys_;
  std::array<double, (1 << kLog2Slots)> values_;
};

/// interpolate_occupancy for many points of one grid that does not change meanwhile, with the
/// same results bit for bit, faster: inlined, the point's scaled coordinates computed once, the
/// last tile looked up remembered, and occupancy_probability read from an exact memo (the cells
/// hold few distinct log-odds values: the clamp bounds and sums of the hit and miss steps).
class OccupancyInterpolator {
 public:
  explicit OccupancyInterpolator(const OccupancyGrid& grid);
  inline BilinearSample operator()(const Eigen::Vector2d& point);

 private:
  using Memo = FloatMemo<9>;
  // cell_probability of interpolate_occupancy: 0.5 for an unknown cell (last_scan 0), else
  // occupancy_probability(log_odds). An unknown cell was never written by OccupancyGrid, so it
  // holds the default log-odds +0 (every write stamps last_scan >= 1), and
  // occupancy_probability(+0) = 1 / (1 + 1) = 0.5 exactly: the memo alone gives both cases.
  double probability(const OccupancyCell& cell) { return (*memo_)(cell.log_odds, occupancy_probability); }

  CornerReader corners_;
  GridGeometry geometry_;
  Memo* memo_;  // this thread's
};

inline BilinearSample OccupancyInterpolator::operator()(const Eigen::Vector2d& point) {
  // in_index_range(point, kMaxCellIndex - 2) and bilinear_corner's (point - origin) / resolution,
  // the same division done once.
  const double sx = (point.x() - geometry_.origin.x()) / geometry_.resolution;
  const double sy = (point.y() - geometry_.origin.y()) / geometry_.resolution;
  constexpr double kLimit = GridGeometry::kMaxCellIndex - 2.0;
  if (!(std::abs(sx) <= kLimit && std::abs(sy) <= kLimit)) return {0.5, Eigen::Vector2d::Zero()};
  const double u = sx - 0.5;
  const double v = sy - 0.5;
  const CellIndex i{GridGeometry::floor_to_int(u), GridGeometry::floor_to_int(v)};
  const double fx = u - i.x;
  const double fy = v - i.y;
  const auto [m00, m10, m01, m11] = corners_(i, [this](const OccupancyCell& cell) { return probability(cell); });
  return bilinear_blend(m00, m10, m01, m11, Eigen::Vector2d(fx, fy), geometry_.resolution);
}

}  // namespace slam2d
