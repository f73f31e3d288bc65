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

/// Eq. (4)-(6) from the four corner values m00 = M(i, j), m10 = M(i + 1, j), m01 = M(i, j + 1),
/// m11 = M(i + 1, j + 1).
BilinearSample bilinear_blend(double m00, double m10, double m01, double m11, const Eigen::Vector2d& fraction,
                              double resolution);

/// Eq. (4)-(6) over any cell value: value_of(CellIndex) -> double. `point` must be finite and
/// within GridGeometry::kMaxCellIndex cells of the origin.
template <typename ValueOf>
BilinearSample interpolate_bilinear(const GridGeometry& geometry, ValueOf&& value_of, const Eigen::Vector2d& point) {
  const BilinearCorner c = bilinear_corner(geometry, point);
  const CellIndex i = c.cell;
  return bilinear_blend(value_of(i), value_of(CellIndex{i.x + 1, i.y}), value_of(CellIndex{i.x, i.y + 1}),
                        value_of(CellIndex{i.x + 1, i.y + 1}), c.fraction, geometry.resolution);
}

/// The corner values m00, m10, m01, m11 of the interpolation square with base cell i of an
/// occupancy grid, each cell read as probability_of(const OccupancyCell&). The four cells are read
/// from one tile when they share it (63 squares in 64 along each axis); a missing tile reads 0.5.
template <typename ProbabilityOf>
std::array<double, 4> occupancy_corners(const OccupancyGrid& grid, CellIndex i, ProbabilityOf&& probability_of) {
  using CellGrid = TiledGrid<OccupancyCell>;
  constexpr int kMask = CellGrid::kTileSize - 1;
  const CellGrid& cells = grid.cells();
  if ((i.x & kMask) != kMask && (i.y & kMask) != kMask) {
    const CellGrid::Tile* tile = cells.find_tile(CellGrid::tile_of(i));
    if (tile == nullptr) return {0.5, 0.5, 0.5, 0.5};
    const int offset = CellGrid::offset_in_tile(i);
    return {probability_of(tile->cells[offset]), probability_of(tile->cells[offset + 1]),
            probability_of(tile->cells[offset + CellGrid::kTileSize]),
            probability_of(tile->cells[offset + CellGrid::kTileSize + 1])};
  }
  return {probability_of(cells.at(i)), probability_of(cells.at({i.x + 1, i.y})), probability_of(cells.at({i.x, i.y + 1})),
          probability_of(cells.at({i.x + 1, i.y + 1}))};
}

/// Eq. (4)-(6) over the occupancy probability of a grid (0.5 in unknown cells): Hector's map
/// value M. A point that is not finite or lies beyond the index range reads 0.5, gradient 0.
BilinearSample interpolate_occupancy(const OccupancyGrid& grid, const Eigen::Vector2d& point);

}  // namespace slam2d
