// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/correlative_grid.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {

struct CorrelativeGrid::Target {
  PointCloud2 cloud;
  std::unique_ptr<KdTree2> tree;  // over cloud.points (this block never moves)
};

namespace {

constexpr double kMaxStoredCells = static_cast<double>(1LL << 28);

/// The kernel of Eq. (1) on a squared distance (m^2): the integer score of a cell centre.
class Kernel {
 public:
  explicit Kernel(double max_distance)
      : max_squared_(max_distance * max_distance), score_per_squared_(kMaxCellScore / max_squared_) {}
  double max_squared() const { return max_squared_; }
  std::uint8_t operator()(double squared_distance) const {
    if (!(squared_distance < max_squared_)) return 0;
    // Round half up; the value is in [0, kMaxCellScore], so this is lround without its call.
    return static_cast<std::uint8_t>(kMaxCellScore - score_per_squared_ * squared_distance + 0.5);
  }

 private:
  double max_squared_;
  double score_per_squared_;
};

double squared_distance_to_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).squaredNorm();
}

const PointCloud2& empty_cloud() {
  static const PointCloud2 cloud;
  return cloud;
}

void check_cloud(const PointCloud2& cloud) {
  check(cloud.normals.empty() || cloud.normals.size() == cloud.points.size(),
        "CorrelativeGrid: the target cloud has normals, but not one per point");
  for (const Point2& p : cloud.points) check(p.allFinite(), "CorrelativeGrid: the target cloud has a non-finite point");
}

// The rasters a thread freed, for its next grids (CorrelativeGrid::Raster). A loop closer builds a
// grid of several megabytes for every chain it matches, hundreds a run; fresh memory each time
// costs the page faults and the kernel's zeroing of every page wherever the allocator hands large
// blocks back to the system at each free, as glibc does above its mmap threshold, which moves
// with the heap's history: graph SLAM on Intel took 5.0 or 9.6 s of CPU for the same run, a third
// of it in those faults. Rasters of at least kMinBytes are kept, kMaxBytes in all at most (8 MB:
// Intel 4.9 s, peak RSS 52 -> 60 MB; 4 MB: 5.7 s, 54 MB; 16 MB: 4.8 s, 69 MB).
class RasterCache {
 public:
  static constexpr std::size_t kMinBytes = std::size_t{1} << 16;
  static constexpr std::size_t kMaxBytes = std::size_t{1} << 23;

  RasterCache() { alive = true; }
  ~RasterCache() { alive = false; }
  RasterCache(const RasterCache&) = delete;
  RasterCache& operator=(const RasterCache&) = delete;

  // `size` zero cells, in the smallest kept raster that holds them.
  std::vector<std::uint8_t> take(std::size_t size) {
    auto best = buffers_.end();
    for (auto it = buffers_.begin(); it != buffers_.end(); ++it) {
      if (it->capacity() >= size && (best == buffers_.end() || it->capacity() < best->capacity())) best = it;
    }
    if (best == buffers_.end()) return std::vector<std::uint8_t>(size, 0);
    std::vector<std::uint8_t> cells = std::move(*best);
    buffers_.erase(best);
    bytes_ -= cells.capacity();
    cells.assign(size, 0);
    return cells;
  }

  // Keeps a freed raster of kMinBytes or more, in place of smaller kept ones beyond kMaxBytes.
  void give(std::vector<std::uint8_t>&& cells) {
    if (cells.capacity() < kMinBytes || cells.capacity() > kMaxBytes) return;
    while (bytes_ + cells.capacity() > kMaxBytes) {
      auto smallest = std::min_element(buffers_.begin(), buffers_.end(),
                                       [](const auto& a, const auto& b) { return a.capacity() < b.capacity(); });
      if (smallest->capacity() >= cells.capacity()) return;
      bytes_ -= smallest->capacity();
      buffers_.erase(smallest);
    }
    bytes_ += cells.capacity();
    buffers_.push_back(std::move(cells));
  }

  // False once this thread's cache is destroyed (a grid freed at the thread's exit after it):
  // a trivially destructible flag, readable to the end.
  static thread_local bool alive;

 private:
  std::vector<std::vector<std::uint8_t>> buffers_;
  std::size_t bytes_ = 0;  // their capacities
};

thread_local bool RasterCache::alive = false;

// This thread's cache, nullptr after its destruction.
RasterCache* raster_cache() {
  static thread_local bool destroyed = false;
  if (destroyed) return nullptr;
  static thread_local RasterCache cache;
  if (!RasterCache::alive) {
    destroyed = true;
    return nullptr;
  }
  return &cache;
}

}  // namespace

CorrelativeGrid::Raster::Raster(std::size_t size) {
  RasterCache* cache = raster_cache();
  cells = cache != nullptr ? cache->take(size) : std::vector<std::uint8_t>(size, 0);
}

CorrelativeGrid::Raster::~Raster() {
  if (RasterCache* cache = raster_cache()) cache->give(std::move(cells));
}

void validate(const CorrelativeGridConfig& config) {
  check_fields(config, "CorrelativeGridConfig");
  check(config.margin / config.resolution <= 1e5, "CorrelativeGridConfig: margin spans more than 10^5 cells");
  check(config.truncation * config.sigma / config.resolution <= 1e4,
        "CorrelativeGridConfig: the kernel radius truncation * sigma spans more than 10^4 cells");
}

CorrelativeGrid::CorrelativeGrid(const PointCloud2& target, const CorrelativeGridConfig& config) : config_(config) {
  validate(config_);
  check_cloud(target);
  geometry_.resolution = config_.resolution;
  auto shared = std::make_shared<Target>();
  shared->cloud = target;
  shared->tree = std::make_unique<KdTree2>(shared->cloud.points);
  if (!target.empty() && !target.has_normals()) estimate_normals(shared->cloud, *shared->tree);
  target_ = std::move(shared);
  if (target.empty()) return;
  rasterize(target);
  pool_levels();
}

/// Level 0 (Eq. (1)): the geometry, then each point's (and segment's) kernel, max-combined.
void CorrelativeGrid::rasterize(const PointCloud2& cloud) {
  const double resolution = config_.resolution;
  const int radius = static_cast<int>(std::ceil(max_distance() / resolution));  // kernel cells
  Eigen::Vector2d low = cloud.points.front();
  Eigen::Vector2d high = low;
  for (const Point2& p : cloud.points) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  // The kernel, then a ring of zero cells (wider by the configured margin).
  const int margin = radius + 1 + static_cast<int>(std::ceil(config_.margin / resolution));
  const Eigen::Vector2d extent = (high - low) / resolution;
  padding_ = (1 << (config_.levels - 1)) - 1;
  const double stored = (extent.x() + 2.0 * (margin + padding_) + 3.0) * (extent.y() + 2.0 * (margin + padding_) + 3.0);
  check(stored <= kMaxStoredCells, "CorrelativeGrid: the table would exceed 2^28 cells per level (target extent " +
                                       std::to_string(high.x() - low.x()) + " x " + std::to_string(high.y() - low.y()) +
                                       " m at " + std::to_string(resolution) + " m per cell)");
  // Half a cell more, so that rounding never puts the lowest point in a cell below `margin`.
  geometry_.origin = low - Eigen::Vector2d::Constant((margin + 0.5) * resolution);
  const CellIndex top = geometry_.cell_of(high);
  width_ = top.x + margin + 1;
  height_ = top.y + margin + 1;
  stride_ = width_ + 2 * padding_;
  stored_rows_ = height_ + 2 * padding_;
  std::vector<std::uint8_t>& cells = levels_.emplace_back(static_cast<std::size_t>(stride_) * stored_rows_).cells;

  const Kernel kernel(max_distance());
  auto splat_point = [&](const Eigen::Vector2d& a) {  // the hot loop: squared distances by rows
    const CellIndex c = geometry_.cell_of(a);
    const Eigen::Vector2d first = geometry_.cell_center({c.x - radius, c.y - radius}) - a;
    for (int v = 0; v <= 2 * radius; ++v) {
      const double dy = first.y() + v * resolution;
      std::uint8_t* row = cells.data() + stored_index(c.x - radius, c.y - radius + v);
      for (int u = 0; u <= 2 * radius; ++u) {
        const double dx = first.x() + u * resolution;
        row[u] = std::max(row[u], kernel(dx * dx + dy * dy));
      }
    }
  };
  auto splat_segment = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const CellIndex c0 = geometry_.cell_of(a.cwiseMin(b));
    const CellIndex c1 = geometry_.cell_of(a.cwiseMax(b));
    for (int y = c0.y - radius; y <= c1.y + radius; ++y) {
      for (int x = c0.x - radius; x <= c1.x + radius; ++x) {
        const double d2 = squared_distance_to_segment(geometry_.cell_center({x, y}), a, b);
        std::uint8_t& cell = cells[static_cast<std::size_t>(stored_index(x, y))];
        cell = std::max(cell, kernel(d2));
      }
    }
  };
  const double max_segment2 = config_.max_segment_length * config_.max_segment_length;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    splat_point(cloud.points[i]);
    if (i + 1 < cloud.size()) {
      const double gap2 = (cloud.points[i + 1] - cloud.points[i]).squaredNorm();
      if (gap2 > 0.0 && gap2 <= max_segment2) splat_segment(cloud.points[i], cloud.points[i + 1]);
    }
  }
}

/// Levels 1 .. levels - 1 (Hess Sec. V-B): level k = max of two level-(k - 1) windows 2^(k-1)
/// apart, along rows then along columns; stored cells beyond the raster count as 0.
void CorrelativeGrid::pool_levels() {
  const std::size_t row = static_cast<std::size_t>(stride_);
  const std::size_t rows = static_cast<std::size_t>(stored_rows_);
  Raster along_rows(row * rows);
  for (int k = 1; k < config_.levels; ++k) {
    const std::size_t shift = std::size_t{1} << (k - 1);
    const std::vector<std::uint8_t>& previous = levels_.back().cells;
    for (std::size_t v = 0; v < rows; ++v) {
      const std::uint8_t* in = previous.data() + v * row;
      std::uint8_t* out = along_rows.cells.data() + v * row;
      const std::size_t inner = row > shift ? row - shift : 0;
      for (std::size_t u = 0; u < inner; ++u) out[u] = std::max(in[u], in[u + shift]);
      for (std::size_t u = inner; u < row; ++u) out[u] = in[u];
    }
    Raster next(row * rows);
    for (std::size_t v = 0; v < rows; ++v) {
      const std::uint8_t* a = along_rows.cells.data() + v * row;
      std::uint8_t* out = next.cells.data() + v * row;
      if (v + shift < rows) {
        const std::uint8_t* b = a + shift * row;
        for (std::size_t u = 0; u < row; ++u) out[u] = std::max(a[u], b[u]);
      } else {
        std::copy(a, a + row, out);
      }
    }
    levels_.push_back(std::move(next));
  }
}

int CorrelativeGrid::score(int level, int x, int y) const {
  if (empty() || level < 0 || level >= levels()) return 0;
  x = std::clamp(x, -padding_, width_ + padding_ - 1);
  y = std::clamp(y, -padding_, height_ + padding_ - 1);
  return levels_[static_cast<std::size_t>(level)].cells[static_cast<std::size_t>(stored_index(x, y))];
}

double CorrelativeGrid::log_likelihood(int score) const {
  return (static_cast<double>(score) / kMaxCellScore - 1.0) * 0.5 * config_.truncation * config_.truncation;
}

double CorrelativeGrid::distance_of_score(int score) const {
  const double s = std::clamp(static_cast<double>(score) / kMaxCellScore, 0.0, 1.0);
  return max_distance() * std::sqrt(1.0 - s);
}

const PointCloud2& CorrelativeGrid::target() const { return target_ ? target_->cloud : empty_cloud(); }

const KdTree2& CorrelativeGrid::tree() const {
  static const KdTree2 empty_tree(empty_cloud().points);
  return target_ ? *target_->tree : empty_tree;
}

std::size_t CorrelativeGrid::memory_bytes() const {
  std::size_t bytes = sizeof(*this);
  for (const Raster& level : levels_) bytes += level.cells.capacity();
  if (target_) bytes += target_->cloud.points.capacity() * sizeof(Point2) * 2;
  return bytes;
}

}  // namespace slam2d
