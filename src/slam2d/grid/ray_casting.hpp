// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Ray casting on a grid: J. E. Bresenham, "Algorithm for computer control of a digital plotter",
// IBM Systems Journal 4(1), 1965. Integer arithmetic only.

#include <algorithm>
#include <cstdlib>
#include <vector>

#include "slam2d/grid/grid_geometry.hpp"

namespace slam2d {

/// Calls visit(CellIndex) for the cells of the 8-connected Bresenham line from `from` up to, and
/// excluding, `to` (nothing when from == to). Along the major axis (the one with the larger
/// |delta|, x on ties) each step moves one cell; the minor coordinate is the one nearest the
/// ideal line, offset k_i = round(i * |d_minor| / |d_major|) with halves rounded toward `to`.
/// Both cells must lie within GridGeometry::kMaxCellIndex of the origin (no overflow then).
template <typename Visit>
void for_each_cell_before(CellIndex from, CellIndex to, Visit&& visit) {
  const int dx = to.x - from.x;
  const int dy = to.y - from.y;
  const int step_x = dx >= 0 ? 1 : -1;
  const int step_y = dy >= 0 ? 1 : -1;
  const int ax = std::abs(dx);
  const int ay = std::abs(dy);
  CellIndex cell = from;
  if (ax >= ay) {
    // Invariant: error = 2 i ay + ax - 2 ax k_i, in [0, 2 ax).
    int error = ax;
    for (int i = 0; i < ax; ++i) {
      visit(cell);
      cell.x += step_x;
      error += 2 * ay;
      if (error >= 2 * ax) {
        cell.y += step_y;
        error -= 2 * ax;
      }
    }
  } else {
    int error = ay;
    for (int i = 0; i < ay; ++i) {
      visit(cell);
      cell.y += step_y;
      error += 2 * ax;
      if (error >= 2 * ay) {
        cell.x += step_x;
        error -= 2 * ay;
      }
    }
  }
}

/// The cells of the Bresenham line from `from` to `to`, both included.
inline std::vector<CellIndex> bresenham_line(CellIndex from, CellIndex to) {
  std::vector<CellIndex> cells;
  cells.reserve(static_cast<std::size_t>(std::max(std::abs(to.x - from.x), std::abs(to.y - from.y))) + 1);
  for_each_cell_before(from, to, [&](CellIndex cell) { cells.push_back(cell); });
  cells.push_back(to);
  return cells;
}

}  // namespace slam2d
