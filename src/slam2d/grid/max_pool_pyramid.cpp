// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/max_pool_pyramid.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr long long kMaxLevelCells = 1LL << 28;

/// The van Herk / Gil-Werman filter with its two buffers, reused across the lines of a level.
class SlidingMax {
 public:
  /// out[j] = max(values[j .. j + window)) for j in [0, n - window], n >= window >= 1.
  void run(const float* values, int n, int window, float* out) {
    prefix_.resize(static_cast<std::size_t>(n));
    suffix_.resize(static_cast<std::size_t>(n));
    float* g = prefix_.data();  // max from the start of each block of `window` samples
    float* h = suffix_.data();  // max to the end of each block
    for (int start = 0; start < n; start += window) {
      const int end = std::min(start + window, n);
      g[start] = values[start];
      for (int i = start + 1; i < end; ++i) g[i] = std::max(g[i - 1], values[i]);
      h[end - 1] = values[end - 1];
      for (int i = end - 2; i >= start; --i) h[i] = std::max(h[i + 1], values[i]);
    }
    // The window [j, j + window) spans the end of j's block and the start of the next one.
    for (int j = 0; j + window <= n; ++j) out[j] = std::max(h[j], g[j + window - 1]);
  }

 private:
  std::vector<float> prefix_;
  std::vector<float> suffix_;
};

/// `count` values with window - 1 outside scores on each side.
void pad_line(const float* values, int count, int window, float outside, std::vector<float>& line) {
  line.assign(static_cast<std::size_t>(count + 2 * (window - 1)), outside);
  std::copy(values, values + count, line.begin() + (window - 1));
}

/// Buffers of one pyramid build, reused from level to level.
struct PoolBuffers {
  SlidingMax filter;
  std::vector<float> line;         // a padded row
  std::vector<float> rows;         // the row pass: height rows of the level's width
  std::vector<float> outside_row;  // a virtual padding row
  std::vector<float> prefix;       // g of one block of rows
  std::vector<float> suffix;       // h of one block of rows
};

void max_into(float* out, const float* a, const float* b, std::size_t n) {
  for (std::size_t u = 0; u < n; ++u) out[u] = std::max(a[u], b[u]);
}

/// The van Herk / Gil-Werman filter down the columns of buffers.rows (height rows of `w`), on
/// whole rows at a time so that every step is a contiguous, vectorisable max of two rows. The
/// columns are padded with window - 1 outside rows at both ends; output row v (of height +
/// window - 1) is max(h[v], g[v + window - 1]), where h comes from v's block of `window` padded
/// rows and g from the next block, so only two blocks are held at a time.
void pool_columns(int height, std::size_t w, int window, float outside_score, PoolBuffers& buffers, float* cells) {
  const int n = height + 2 * (window - 1);  // padded rows
  const int out_rows = height + window - 1;
  buffers.outside_row.assign(w, outside_score);
  auto row = [&](int i) {
    const int y = i - (window - 1);
    return y < 0 || y >= height ? buffers.outside_row.data() : buffers.rows.data() + static_cast<std::size_t>(y) * w;
  };
  buffers.prefix.resize(static_cast<std::size_t>(window) * w);
  buffers.suffix.resize(static_cast<std::size_t>(window) * w);
  float* g = buffers.prefix.data();
  float* h = buffers.suffix.data();
  auto block_suffix = [&](int start) {  // h over padded rows [start, end), stored from h[0]
    const int end = std::min(start + window, n);
    std::copy(row(end - 1), row(end - 1) + w, h + static_cast<std::size_t>(end - 1 - start) * w);
    for (int i = end - 2; i >= start; --i) {
      max_into(h + static_cast<std::size_t>(i - start) * w, h + static_cast<std::size_t>(i + 1 - start) * w, row(i), w);
    }
  };
  auto block_prefix = [&](int start) {  // g over padded rows [start, end), stored from g[0]
    const int end = std::min(start + window, n);
    std::copy(row(start), row(start) + w, g);
    for (int i = start + 1; i < end; ++i) {
      max_into(g + static_cast<std::size_t>(i - start) * w, g + static_cast<std::size_t>(i - 1 - start) * w, row(i), w);
    }
  };
  for (int start = 0; start < out_rows; start += window) {
    block_suffix(start);
    if (start + window < n) block_prefix(start + window);
    for (int j = 0; j < window && start + j < out_rows; ++j) {
      float* out = cells + static_cast<std::size_t>(start + j) * w;
      if (j == 0) {
        std::copy(h, h + w, out);  // the window is exactly this block
      } else {
        max_into(out, h + static_cast<std::size_t>(j) * w, g + static_cast<std::size_t>(j - 1) * w, w);
      }
    }
  }
}

/// Level cells: the row pass into buffers.rows, then the column pass into `cells`.
void pool_level(int width, int height, std::span<const float> scores, int window, float outside_score,
                PoolBuffers& buffers, std::vector<float>& cells) {
  const auto w = static_cast<std::size_t>(width + window - 1);
  buffers.rows.resize(w * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {  // rows[y][u] = max of row y over [u - offset, u - offset + window)
    pad_line(scores.data() + static_cast<std::size_t>(y) * width, width, window, outside_score, buffers.line);
    buffers.filter.run(buffers.line.data(), static_cast<int>(buffers.line.size()), window,
                       buffers.rows.data() + static_cast<std::size_t>(y) * w);
  }
  cells.resize(w * static_cast<std::size_t>(height + window - 1));
  pool_columns(height, w, window, outside_score, buffers, cells.data());
}

void validate(int width, int height, std::span<const float> scores, const MaxPoolPyramidConfig& config) {
  check(width >= 0 && height >= 0, "MaxPoolPyramid: negative grid size");
  check_fields(config, "MaxPoolPyramidConfig");
  check(!std::isnan(config.outside_score), "MaxPoolPyramid: outside_score is NaN");
  const long long window = 1LL << (config.levels - 1);
  check((width + window - 1) * (height + window - 1) <= kMaxLevelCells,
        "MaxPoolPyramid: a level would have more than 2^28 cells");
  check(static_cast<long long>(scores.size()) == static_cast<long long>(width) * height,
        "MaxPoolPyramid: expected " + std::to_string(static_cast<long long>(width) * height) + " scores, got " +
            std::to_string(scores.size()));
  check(std::none_of(scores.begin(), scores.end(), [](float s) { return std::isnan(s); }), "MaxPoolPyramid: NaN score");
}

}  // namespace

void sliding_window_max(std::span<const float> values, int window, std::span<float> out) {
  check(window >= 1 && static_cast<std::size_t>(window) <= values.size(),
        "sliding_window_max: the window must hold 1 to values.size() samples");
  check(out.size() == values.size() - static_cast<std::size_t>(window) + 1,
        "sliding_window_max: the output must have values.size() - window + 1 samples");
  SlidingMax filter;
  filter.run(values.data(), static_cast<int>(values.size()), window, out.data());
}

MaxPoolPyramid::MaxPoolPyramid(int width, int height, std::span<const float> scores, const MaxPoolPyramidConfig& config)
    : width_(width), height_(height), outside_score_(config.outside_score) {
  validate(width, height, scores, config);
  levels_.resize(static_cast<std::size_t>(config.levels));
  PoolBuffers buffers;
  for (int k = 0; k < config.levels; ++k) {
    Level& level = levels_[static_cast<std::size_t>(k)];
    level.offset = window(k) - 1;
    if (width == 0 || height == 0) continue;  // every window misses the grid: at() returns outside_score
    level.width = width + window(k) - 1;
    level.height = height + window(k) - 1;
    pool_level(width, height, scores, window(k), outside_score_, buffers, level.cells);
  }
}

std::size_t MaxPoolPyramid::memory_bytes() const {
  std::size_t bytes = sizeof(*this);
  for (const Level& level : levels_) bytes += sizeof(Level) + level.cells.capacity() * sizeof(float);
  return bytes;
}

}  // namespace slam2d
