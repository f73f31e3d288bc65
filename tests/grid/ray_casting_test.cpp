// SPDX-License-Identifier: BSD-3-Clause
// Bresenham ray casting against a brute-force reference.

#include "slam2d/grid/ray_casting.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <vector>

namespace slam2d {
namespace {

/// Brute force: for each step i along the major axis, try every minor offset k in [0, |d_minor|]
/// and keep the one nearest the ideal line (|2 k |d_major| - 2 i |d_minor|| smallest), ties to
/// the larger k (toward the end cell).
std::vector<CellIndex> reference_line(CellIndex a, CellIndex b) {
  const int dx = b.x - a.x;
  const int dy = b.y - a.y;
  const bool x_major = std::abs(dx) >= std::abs(dy);
  const int major = x_major ? std::abs(dx) : std::abs(dy);
  const int minor = x_major ? std::abs(dy) : std::abs(dx);
  const int s_major = (x_major ? dx : dy) >= 0 ? 1 : -1;
  const int s_minor = (x_major ? dy : dx) >= 0 ? 1 : -1;
  std::vector<CellIndex> cells;
  for (int i = 0; i <= major; ++i) {
    int best = 0;
    long long best_error = -1;
    for (int k = 0; k <= minor; ++k) {
      const long long error = std::llabs(2LL * k * major - 2LL * i * minor);
      if (best_error < 0 || error <= best_error) {
        best = k;
        best_error = error;
      }
    }
    cells.push_back(x_major ? CellIndex{a.x + s_major * i, a.y + s_minor * best}
                            : CellIndex{a.x + s_minor * best, a.y + s_major * i});
  }
  return cells;
}

TEST(RayCasting, MatchesBruteForceOnRandomSegments) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coordinate(-60, 60);
  for (int trial = 0; trial < 3000; ++trial) {
    const CellIndex a{coordinate(rng), coordinate(rng)};
    const CellIndex b{coordinate(rng), coordinate(rng)};
    const std::vector<CellIndex> line = bresenham_line(a, b);
    const std::vector<CellIndex> expected = reference_line(a, b);
    ASSERT_EQ(line.size(), expected.size()) << a.x << "," << a.y << " -> " << b.x << "," << b.y;
    for (std::size_t i = 0; i < line.size(); ++i) {
      ASSERT_EQ(line[i], expected[i]) << "cell " << i << " of " << a.x << "," << a.y << " -> " << b.x << "," << b.y;
    }
    // Endpoints and 8-connectivity: one step along the major axis, at most one along the minor.
    ASSERT_EQ(line.front(), a);
    ASSERT_EQ(line.back(), b);
    const std::size_t steps = static_cast<std::size_t>(std::max(std::abs(b.x - a.x), std::abs(b.y - a.y)));
    ASSERT_EQ(line.size(), steps + 1);
    for (std::size_t i = 1; i < line.size(); ++i) {
      const CellIndex d = line[i] - line[i - 1];
      ASSERT_LE(std::abs(d.x), 1);
      ASSERT_LE(std::abs(d.y), 1);
      ASSERT_EQ(std::max(std::abs(d.x), std::abs(d.y)), 1);
    }
  }
}

TEST(RayCasting, HandComputedLines) {
  // (0,0) -> (5,2): offsets round(2i/5) = 0 0 1 1 2 2.
  EXPECT_EQ(bresenham_line({0, 0}, {5, 2}),
            (std::vector<CellIndex>{{0, 0}, {1, 0}, {2, 1}, {3, 1}, {4, 2}, {5, 2}}));
  // Steep and backwards: (0,0) -> (-1,-3): offsets round(i/3) = 0 0 1 1 (the half at i = 1.5 does not occur).
  EXPECT_EQ(bresenham_line({0, 0}, {-1, -3}), (std::vector<CellIndex>{{0, 0}, {0, -1}, {-1, -2}, {-1, -3}}));
  // A tie (offset 0.5 at i = 1) rounds toward the end cell.
  EXPECT_EQ(bresenham_line({0, 0}, {2, 1}), (std::vector<CellIndex>{{0, 0}, {1, 1}, {2, 1}}));
  EXPECT_EQ(bresenham_line({3, 3}, {3, 3}), (std::vector<CellIndex>{{3, 3}}));
}

TEST(RayCasting, ForEachCellBeforeExcludesTheEndCell) {
  std::vector<CellIndex> visited;
  for_each_cell_before({2, -1}, {-3, -1}, [&](CellIndex c) { visited.push_back(c); });
  EXPECT_EQ(visited, (std::vector<CellIndex>{{2, -1}, {1, -1}, {0, -1}, {-1, -1}, {-2, -1}}));
  visited.clear();
  for_each_cell_before({4, 4}, {4, 4}, [&](CellIndex c) { visited.push_back(c); });
  EXPECT_TRUE(visited.empty());
}

TEST(GridGeometry, CellOfFloorsAndCentresRoundTrip) {
  const GridGeometry geometry{0.25, Eigen::Vector2d(-1.0, 2.0)};
  EXPECT_EQ(geometry.cell_of({-1.0, 2.0}), (CellIndex{0, 0}));
  EXPECT_EQ(geometry.cell_of({-1.01, 1.99}), (CellIndex{-1, -1}));  // floor, not truncation
  EXPECT_EQ(geometry.cell_of({0.3, 2.6}), (CellIndex{5, 2}));
  EXPECT_EQ(geometry.cell_center({5, 2}), Eigen::Vector2d(0.375, 2.625));
  for (int x = -20; x <= 20; ++x) {
    for (int y = -20; y <= 20; ++y) EXPECT_EQ(geometry.cell_of(geometry.cell_center({x, y})), (CellIndex{x, y}));
  }
  EXPECT_FALSE(geometry.in_index_range({std::nan(""), 0.0}));
  EXPECT_FALSE(geometry.in_index_range({1e12, 0.0}));
  EXPECT_TRUE(geometry.in_index_range({1e6, -1e6}));
}

}  // namespace
}  // namespace slam2d
