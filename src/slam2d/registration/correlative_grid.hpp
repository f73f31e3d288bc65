// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The rasterised lookup table of correlative scan matching: E. Olson, "Real-time correlative scan
// matching", ICRA 2009, Sec. III-B (the table) and Sec. IV (the low-resolution table), with the
// max-pooled levels of W. Hess, D. Kohler, H. Rapp, D. Andor, "Real-time loop closure in 2D LIDAR
// SLAM", ICRA 2016, Sec. V-B (the precomputed grids that bound branch-and-bound).
//
// Level 0 holds, at each cell, the log-likelihood of a source point landing at the cell's centre:
// a Gaussian of the distance d to the nearest target point (or segment, see max_segment_length),
// truncated at d_max = truncation * sigma, shifted and scaled to an integer score
//   s(d) = round(kMaxCellScore (1 - d^2 / d_max^2)) for d < d_max, else 0,
// so that log p(d) = -d^2 / (2 sigma^2) = (s / kMaxCellScore - 1) truncation^2 / 2     Eq. (1)
// (Olson: the table is the max over the target points of their log-likelihood kernels). Level k
// holds at cell (x, y) the maximum of the level-0 cells [x, x + 2^k) x [y, y + 2^k) at the same
// resolution (Hess: "precomputation grids"), so the level-k score of a translation bounds the
// level-0 score of every translation in the 2^k x 2^k cells above it (Olson Sec. IV). Integer
// scores make every sum exact: bounds and ties compare without rounding.
//
// Storage: every level is a row-major byte raster padded by `padding() = 2^(levels - 1) - 1`
// cells on each side, and the data region keeps a ring of zero cells, so any cell index clamped
// to the stored range reads the exact value of every level (0 outside). A grid is an immutable
// value: build it once from a cloud (one scan or the aggregate of several, in any one frame) and
// match many scans against it.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/grid/grid_geometry.hpp"

namespace slam2d {

class KdTree2;

/// Score of a cell on a target point (d = 0); a cell beyond d_max scores 0.
inline constexpr int kMaxCellScore = 255;

struct CorrelativeGridConfig {
  double resolution = 0.03;
  double sigma = 0.03;
  double truncation = 3.0;
  double max_segment_length = 0.0;
  int levels = 8;
  double margin = 0.0;
};

template <typename Fields>
void describe(Fields& f, CorrelativeGridConfig& c) {
  f.number("resolution", c.resolution, "m per cell", greater_than(0), "(Olson: 0.03 m)");
  f.number("sigma", c.sigma, "m", greater_than(0), "standard deviation of a point's distance to its target point");
  f.number("truncation", c.truncation, "sigmas", greater_than(0), "the log-likelihood is floored at d_max = truncation * sigma");
  f.number("max_segment_length", c.max_segment_length, "m", at_least(0),
           "consecutive target points closer than this are joined by a segment, whose distance counts too (0: points only, as Olson)");
  f.number("levels", c.levels, "1", between(1, 16), "max-pooled levels 0 .. levels - 1 (level k pools 2^k cells)");
  f.number("margin", c.margin, "m", at_least(0),
           "zero cells stored beyond the kernel around the target, so that a search window reaching that far past the target reads cells directly");
}

class CorrelativeGrid {
 public:
  /// An empty grid (no target): every cell scores 0.
  CorrelativeGrid() = default;
  /// Rasterises the target cloud (any frame; its points in order when max_segment_length > 0).
  /// Target normals are kept, or estimated from the nearest neighbours when the cloud has none
  /// (for the degeneracy analysis of matches). Throws Error for an invalid configuration, a
  /// non-finite point, or a grid over 2^28 cells per level.
  explicit CorrelativeGrid(const PointCloud2& target, const CorrelativeGridConfig& config = {});

  bool empty() const { return width_ == 0; }
  const CorrelativeGridConfig& config() const { return config_; }
  /// Cell (0, 0) of level 0, in the target's frame.
  const GridGeometry& geometry() const { return geometry_; }
  double resolution() const { return geometry_.resolution; }
  /// Cells of the data region (target box, kernel radius and a zero ring), level 0.
  int width() const { return width_; }
  int height() const { return height_; }
  int levels() const { return static_cast<int>(levels_.size()); }
  /// Zero cells stored on each side beyond the data region.
  int padding() const { return padding_; }
  /// Stored cells per row: width() + 2 padding().
  int stride() const { return stride_; }
  /// Stored rows: height() + 2 padding().
  int stored_rows() const { return stored_rows_; }
  /// d_max (m): beyond it a point scores 0.
  double max_distance() const { return config_.truncation * config_.sigma; }

  /// Level-`level` score at cell (x, y) (any ints; 0 outside). level in [0, levels()).
  int score(int level, int x, int y) const;
  /// The stored raster of a level: cell (x, y), with x in [-padding, width + padding), at
  /// stored_index(x, y). For matchers' inner loops.
  const std::uint8_t* level_data(int level) const { return levels_[static_cast<std::size_t>(level)].cells.data(); }
  std::ptrdiff_t stored_index(int x, int y) const {
    return static_cast<std::ptrdiff_t>(y + padding_) * stride_ + (x + padding_);
  }
  /// Eq. (1): log p of a cell score (score 0: the truncation floor).
  double log_likelihood(int score) const;
  /// The distance (m) a positive score stands for, d_max sqrt(1 - s / kMaxCellScore); d_max for 0.
  double distance_of_score(int score) const;

  /// The target cloud, with normals (some may be zero: no normal), and a kd-tree over it.
  const PointCloud2& target() const;
  const KdTree2& tree() const;
  std::size_t memory_bytes() const;

 private:
  struct Target;

  void rasterize(const PointCloud2& cloud);
  void pool_levels();

  CorrelativeGridConfig config_;
  GridGeometry geometry_;
  int width_ = 0;
  int height_ = 0;
  int padding_ = 0;
  int stride_ = 0;
  int stored_rows_ = 0;
  // One level's cells. Its memory comes from, and goes back to, a few rasters this thread freed
  // (correlative_grid.cpp): a loop closer builds a grid of megabytes for every chain it matches.
  struct Raster {
    std::vector<std::uint8_t> cells;
    explicit Raster(std::size_t size);  // size cells, all 0
    Raster(const Raster&) = default;
    Raster(Raster&&) noexcept = default;
    Raster& operator=(const Raster&) = default;
    Raster& operator=(Raster&&) noexcept = default;
    ~Raster();
  };
  std::vector<Raster> levels_;
  std::shared_ptr<const Target> target_;  // immutable, shared by copies
};

/// Throws Error unless the configuration is valid (ranges on CorrelativeGridConfig).
void validate(const CorrelativeGridConfig& config);

}  // namespace slam2d
