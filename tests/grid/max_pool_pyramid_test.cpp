// SPDX-License-Identifier: BSD-3-Clause
// Max-pooled pyramid (Olson 2009; Cartographer's PrecomputationGrid2D) against brute-force
// maxima over windows, and the van Herk / Gil-Werman sliding maximum against brute force.

#include "slam2d/grid/max_pool_pyramid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"

namespace slam2d {
namespace {

std::vector<float> random_scores(int width, int height, Rng& rng) {
  std::vector<float> scores(static_cast<std::size_t>(width) * height);
  for (float& score : scores) score = static_cast<float>(rng.uniform(0.0, 1.0));
  return scores;
}

/// Max of scores over [x, x + window) x [y, y + window), cells outside the grid counting as `outside`.
float brute_force_max(int width, int height, const std::vector<float>& scores, int x, int y, int window, float outside) {
  float best = -std::numeric_limits<float>::infinity();
  for (int v = y; v < y + window; ++v) {
    for (int u = x; u < x + window; ++u) {
      const bool inside = u >= 0 && v >= 0 && u < width && v < height;
      best = std::max(best, inside ? scores[static_cast<std::size_t>(v) * width + u] : outside);
    }
  }
  return best;
}

void expect_matches_brute_force(int width, int height, const std::vector<float>& scores,
                                const MaxPoolPyramidConfig& config) {
  const MaxPoolPyramid pyramid(width, height, scores, config);
  ASSERT_EQ(pyramid.levels(), config.levels);
  for (int level = 0; level < pyramid.levels(); ++level) {
    const int window = MaxPoolPyramid::window(level);
    // Every stored cell, plus a ring of cells beyond (whose windows miss the grid).
    for (int y = -window - 1; y <= height + 1; ++y) {
      for (int x = -window - 1; x <= width + 1; ++x) {
        ASSERT_EQ(pyramid.at(level, x, y), brute_force_max(width, height, scores, x, y, window, config.outside_score))
            << "level " << level << " cell " << x << ", " << y << " grid " << width << " x " << height;
      }
    }
  }
}

TEST(SlidingWindowMax, MatchesBruteForce) {
  Rng rng(1);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + static_cast<int>(rng.uniform_index(50));
    const int window = 1 + static_cast<int>(rng.uniform_index(static_cast<std::size_t>(n)));
    const std::vector<float> values = random_scores(n, 1, rng);
    std::vector<float> out(static_cast<std::size_t>(n - window + 1));
    sliding_window_max(values, window, out);
    for (int j = 0; j + window <= n; ++j) {
      const float expected = *std::max_element(values.begin() + j, values.begin() + j + window);
      ASSERT_EQ(out[static_cast<std::size_t>(j)], expected) << "n " << n << " window " << window << " j " << j;
    }
  }
}

TEST(SlidingWindowMax, HandComputed) {
  const std::vector<float> values{1, 5, 2, 0, 3, 4, 1};
  std::vector<float> out(5);
  sliding_window_max(values, 3, out);
  EXPECT_EQ(out, (std::vector<float>{5, 5, 3, 4, 4}));
  EXPECT_THROW(sliding_window_max(values, 0, out), Error);
  EXPECT_THROW(sliding_window_max(values, 8, out), Error);
  EXPECT_THROW(sliding_window_max(values, 2, out), Error);  // output of the wrong size
}

TEST(MaxPoolPyramid, RandomGridsMatchBruteForceOverWindows) {
  Rng rng(2);
  for (int trial = 0; trial < 25; ++trial) {
    const int width = 1 + static_cast<int>(rng.uniform_index(30));
    const int height = 1 + static_cast<int>(rng.uniform_index(30));
    const float outside = trial % 2 == 0 ? 0.0f : 0.5f;  // 0.5 lies inside the score range: windows mix
    expect_matches_brute_force(width, height, random_scores(width, height, rng),
                               {.levels = 6, .outside_score = outside});
  }
}

TEST(MaxPoolPyramid, SingleRowsColumnsAndCells) {
  Rng rng(3);
  for (const auto& [width, height] : std::vector<std::pair<int, int>>{{1, 1}, {1, 20}, {20, 1}, {3, 2}}) {
    expect_matches_brute_force(width, height, random_scores(width, height, rng), {.levels = 5, .outside_score = 0.1f});
  }
}

TEST(MaxPoolPyramid, LevelZeroIsTheInputAndLevelsBoundTheLevelBelow) {
  Rng rng(4);
  const int width = 37;
  const int height = 23;
  const std::vector<float> scores = random_scores(width, height, rng);
  const MaxPoolPyramid pyramid(width, height, scores, {.levels = 7});
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) EXPECT_EQ(pyramid.at(0, x, y), scores[static_cast<std::size_t>(y) * width + x]);
  }
  // The bound property branch-and-bound relies on: a level-k cell bounds the level-(k-1) cells
  // of its window (its window is the union of theirs).
  for (int level = 1; level < pyramid.levels(); ++level) {
    const int half = MaxPoolPyramid::window(level - 1);
    for (int y = -2 * half; y < height; ++y) {
      for (int x = -2 * half; x < width; ++x) {
        const float children = std::max({pyramid.at(level - 1, x, y), pyramid.at(level - 1, x + half, y),
                                         pyramid.at(level - 1, x, y + half), pyramid.at(level - 1, x + half, y + half)});
        ASSERT_EQ(pyramid.at(level, x, y), children);
      }
    }
  }
  // The top level's window (64 cells) covers the whole grid from (0, 0).
  EXPECT_EQ(pyramid.at(6, 0, 0), *std::max_element(scores.begin(), scores.end()));
}

TEST(MaxPoolPyramid, EmptyGridIsOutsideEverywhere) {
  const MaxPoolPyramid pyramid(0, 5, {}, {.levels = 3, .outside_score = -1.0f});
  EXPECT_EQ(pyramid.at(0, 0, 0), -1.0f);
  EXPECT_EQ(pyramid.at(2, -1, 2), -1.0f);
}

TEST(MaxPoolPyramid, RejectsBadInput) {
  const std::vector<float> scores(6, 0.5f);
  EXPECT_THROW(MaxPoolPyramid(2, 2, scores), Error);  // wrong count
  EXPECT_THROW(MaxPoolPyramid(-2, -3, scores), Error);
  EXPECT_THROW(MaxPoolPyramid(3, 2, scores, {.levels = 0}), Error);
  EXPECT_THROW(MaxPoolPyramid(3, 2, scores, {.levels = 17}), Error);
  EXPECT_THROW(MaxPoolPyramid(3, 2, scores, {.outside_score = std::numeric_limits<float>::quiet_NaN()}), Error);
  std::vector<float> with_nan = scores;
  with_nan[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(MaxPoolPyramid(3, 2, with_nan), Error);
}

}  // namespace
}  // namespace slam2d
