// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Max-pooled pyramid of a score grid, the bounds of correlative branch-and-bound matching:
// E. Olson, "Real-time correlative scan matching", ICRA 2009 (the low-resolution maximum map), in
// the form of Cartographer's PrecomputationGrid2D (W. Hess, D. Kohler, H. Rapp, D. Andor,
// "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, the precomputed grids): every level keeps
// the resolution of level 0, and level k holds at cell (x, y) the maximum of the level-0 cells
// [x, x + 2^k) x [y, y + 2^k). A level-k lookup therefore bounds the score of every translation
// within that window, and cells are stored from x = -(2^k - 1) so that windows hanging over the
// grid's lower edges are covered too.
//
// Each level is computed from level 0 by a separable sliding-window maximum, rows then columns,
// with the van Herk / Gil-Werman algorithm (M. van Herk, "A fast algorithm for local minimum and
// maximum filters on rectangular and octagonal kernels", Pattern Recognition Letters 13, 1992;
// J. Gil and M. Werman, "Computing 2-D min, median, and max filters", IEEE PAMI 15, 1993): three
// comparisons per cell and pass whatever the window, so O(cells) per level.

#include <cstddef>
#include <span>
#include <vector>

#include "slam2d/core/config_fields.hpp"

namespace slam2d {

struct MaxPoolPyramidConfig {
  int levels = 7;
  // Score of every cell beyond the input grid (the lowest score, usually; any but NaN). Not in
  // the table: a float, set by the matcher that builds the pyramid, not by a user.
  float outside_score = 0.0f;
};

template <typename Fields>
void describe(Fields& f, MaxPoolPyramidConfig& c) {
  f.number("levels", c.levels, "1", between(1, 16), "levels 0 .. levels - 1, level k pools 2^k x 2^k cells");
}

/// 1D sliding-window maximum (van Herk / Gil-Werman): out[j] = max(values[j .. j + window)) for
/// j in [0, values.size() - window]. Throws Error for window < 1, window > values.size() or an
/// output of another size than values.size() - window + 1.
void sliding_window_max(std::span<const float> values, int window, std::span<float> out);

class MaxPoolPyramid {
 public:
  /// Pools a row-major width x height grid of scores (cell (x, y) at index y * width + x).
  /// Throws Error for negative sizes, a score count other than width * height, a NaN score, an
  /// invalid configuration, or a pyramid over 2^28 cells per level.
  MaxPoolPyramid(int width, int height, std::span<const float> scores, const MaxPoolPyramidConfig& config = {});

  /// Max of the level-0 cells [x, x + 2^level) x [y, y + 2^level), cells beyond the input counting
  /// as outside_score (so outside_score when the window misses the grid). level in [0, levels()).
  float at(int level, int x, int y) const {
    const Level& l = levels_[static_cast<std::size_t>(level)];
    const int u = x + l.offset;
    const int v = y + l.offset;
    if (u < 0 || v < 0 || u >= l.width || v >= l.height) return outside_score_;
    return l.cells[static_cast<std::size_t>(v) * l.width + u];
  }
  int levels() const { return static_cast<int>(levels_.size()); }
  /// Size of level 0 (the input grid).
  int width() const { return width_; }
  int height() const { return height_; }
  /// Cells along the side of a level's window: 2^level.
  static int window(int level) { return 1 << level; }
  float outside_score() const { return outside_score_; }
  std::size_t memory_bytes() const;

 private:
  struct Level {
    int offset = 0;  // 2^k - 1: stored cell u holds the window starting at x = u - offset
    int width = 0;   // input width + 2^k - 1
    int height = 0;  // input height + 2^k - 1
    std::vector<float> cells;
  };

  int width_ = 0;
  int height_ = 0;
  float outside_score_ = 0.0f;
  std::vector<Level> levels_;
};

}  // namespace slam2d
