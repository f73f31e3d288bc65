// SPDX-License-Identifier: BSD-3-Clause
// TiledGrid: growth, default reads, bounding box, copy-on-write, and copies that share tiles
// written from several threads at once.

#include "slam2d/grid/tiled_grid.hpp"

#include "slam2d/grid/ray_casting.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <thread>
#include <utility>
#include <vector>

namespace slam2d {
namespace {

using IntGrid = TiledGrid<int>;

TEST(TiledGrid, ReadsOfUntouchedCellsReturnTheDefaultWithoutAllocating) {
  const IntGrid grid(-7);
  const std::size_t bytes = grid.memory_bytes();
  for (int x = -500; x <= 500; x += 37) EXPECT_EQ(grid.at({x, -x}), -7);
  EXPECT_EQ(grid.tile_count(), 0u);
  EXPECT_EQ(grid.memory_bytes(), bytes);
  EXPECT_TRUE(grid.bounding_box().empty());
}

TEST(TiledGrid, TileIndexingFloorsNegativeCells) {
  EXPECT_EQ(IntGrid::tile_of({-1, -64}), (CellIndex{-1, -1}));
  EXPECT_EQ(IntGrid::tile_of({-65, 63}), (CellIndex{-2, 0}));
  EXPECT_EQ(IntGrid::offset_in_tile({-1, -1}), 64 * 64 - 1);
  EXPECT_EQ(IntGrid::offset_in_tile({64, 65}), 64);
}

TEST(TiledGrid, GrowsInEveryDirectionAndKeepsValues) {
  IntGrid grid;
  std::map<std::pair<int, int>, int> truth;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> coordinate(-3000, 3000);
  CellBox box;
  for (int i = 0; i < 300; ++i) {
    const CellIndex cell{coordinate(rng), coordinate(rng)};
    const int value = static_cast<int>(rng() % 1000) + 1;
    grid.mutable_at(cell) = value;
    truth[{cell.x, cell.y}] = value;
    box.extend(cell);
  }
  for (const auto& [xy, value] : truth) ASSERT_EQ(grid.at({xy.first, xy.second}), value);
  EXPECT_EQ(grid.bounding_box(), box);
  EXPECT_LT(box.min.x, -2900);  // the random cells reached every side
  EXPECT_GT(box.max.y, 2900);
  EXPECT_EQ(grid.at({box.min.x - 1, box.min.y}), 0);
}

TEST(TiledGrid, MemoryFollowsTheWrittenArea) {
  IntGrid grid;
  for (int x = -1000; x < 1000; ++x) grid.mutable_at({x, 5}) = 1;  // one row of 2000 cells
  // Cells -1000..999 span tiles floor(-1000/64) = -16 .. floor(999/64) = 15: 32 tiles, all in tile row 0.
  EXPECT_EQ(grid.tile_count(), 32u);
  EXPECT_LT(grid.memory_bytes(), 33 * sizeof(IntGrid::Tile) + 4096);
  EXPECT_EQ(grid.bounding_box(), (CellBox{{-1000, 5}, {999, 5}}));
}

TEST(TiledGrid, CopyOnWrite) {
  IntGrid original;
  const CellIndex a{1, 1};      // tile (0, 0)
  const CellIndex b{-100, 3};   // tile (-2, 0)
  const CellIndex c{10, 500};   // tile (0, 7)
  original.mutable_at(a) = 1;
  original.mutable_at(b) = 2;
  original.mutable_at(c) = 3;

  IntGrid copy = original;  // shares all three tiles
  EXPECT_TRUE(copy.shares_tile_with(original, a));
  EXPECT_TRUE(copy.shares_tile_with(original, b));
  EXPECT_TRUE(copy.shares_tile_with(original, c));

  copy.mutable_at({2, 2}) = 42;  // tile (0, 0) is copied first
  EXPECT_EQ(copy.at({2, 2}), 42);
  EXPECT_EQ(original.at({2, 2}), 0);
  EXPECT_EQ(copy.at(a), 1);  // the copy kept the rest of the tile
  EXPECT_FALSE(copy.shares_tile_with(original, a));
  EXPECT_TRUE(copy.shares_tile_with(original, b));  // untouched tiles are still shared
  EXPECT_TRUE(copy.shares_tile_with(original, c));

  original.mutable_at(b) = -2;  // and the other way round
  EXPECT_EQ(copy.at(b), 2);
  EXPECT_FALSE(copy.shares_tile_with(original, b));
  EXPECT_TRUE(copy.shares_tile_with(original, c));

  copy.mutable_at({5000, 5000}) = 9;  // a new tile in the copy only
  EXPECT_EQ(original.at({5000, 5000}), 0);
  EXPECT_EQ(original.tile_count(), 3u);
  EXPECT_EQ(copy.tile_count(), 4u);
}

TEST(TiledGrid, ASecondWriteToAnUnsharedTileDoesNotCopyAgain) {
  IntGrid original;
  original.mutable_at({0, 0}) = 1;
  IntGrid copy = original;
  int* first = &copy.mutable_at({0, 0});
  int* second = &copy.mutable_at({0, 0});
  EXPECT_EQ(first, second);
  EXPECT_NE(first, &original.mutable_at({0, 0}));
}

TEST(TiledGrid, UpdateRayVisitsTheBresenhamCellsInOrder) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> coordinate(-300, 300);
  for (int trial = 0; trial < 400; ++trial) {
    IntGrid grid;
    CellIndex from{coordinate(rng), coordinate(rng)};
    CellIndex to{coordinate(rng), coordinate(rng)};
    if (trial % 4 == 0) to.y = from.y;  // axis-aligned rays too
    if (trial % 4 == 1) to.x = from.x;
    if (trial % 4 == 2) to = {from.x + (to.x - from.x) / 4, from.y - (to.x - from.x) / 4};  // diagonals
    int visits = 0;
    grid.update_ray(from, to, [&](int& cell) { cell = ++visits; });
    std::vector<CellIndex> expected = bresenham_line(from, to);
    expected.pop_back();  // the end cell is not visited
    ASSERT_EQ(visits, static_cast<int>(expected.size()));
    CellBox box;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      ASSERT_EQ(grid.at(expected[i]), static_cast<int>(i) + 1) << "trial " << trial << " cell " << i;
      box.extend(expected[i]);
    }
    EXPECT_EQ(grid.bounding_box(), box);
    EXPECT_EQ(grid.at(to), 0);
  }
}

TEST(TiledGrid, UpdateRayIsExactForVeryLongRays) {
  // The fixed-point walk is exact up to kMaxFixedPointRay cells; longer rays take the slow path.
  const int n = IntGrid::kMaxFixedPointRay;
  const CellIndex rays[][2] = {{{0, 0}, {n, n - 1}},           // worst case for the fixed-point rounding
                               {{5, -3}, {5 - 12345, -3 - n}},  // steep, backwards
                               {{0, 0}, {n + 1, 7}},            // beyond: Bresenham error term
                               {{-1, 2}, {-1 - (n + 10), 2 + (n + 9)}}};
  for (const auto& ray : rays) {
    IntGrid grid;
    int visits = 0;
    grid.update_ray(ray[0], ray[1], [&](int& cell) { cell = ++visits; });
    const std::vector<CellIndex> expected = bresenham_line(ray[0], ray[1]);
    ASSERT_EQ(visits + 1, static_cast<int>(expected.size()));
    for (int i = 0; i < visits; ++i) ASSERT_EQ(grid.at(expected[static_cast<std::size_t>(i)]), i + 1) << i;
  }
}

TEST(TiledGrid, UpdateRayCopiesSharedTilesFirst) {
  IntGrid original;
  original.mutable_at({0, 0}) = 5;
  original.mutable_at({200, 0}) = 6;
  IntGrid copy = original;
  copy.update_ray({0, 0}, {10, 0}, [](int& cell) { cell += 1; });
  EXPECT_EQ(copy.at({0, 0}), 6);
  EXPECT_EQ(original.at({0, 0}), 5);
  EXPECT_EQ(original.at({5, 0}), 0);
  EXPECT_TRUE(copy.shares_tile_with(original, {200, 0}));
}

TEST(TiledGrid, CopiesSharingTilesCanBeReadAndWrittenFromSeveralThreads) {
  // Eight copies of one grid share its 16 tiles; eight threads each read all of their own copy
  // and write into it (every tile, starting at a different one, so that several threads un-share
  // the same tile at the same moment, and so that some see it still shared and copy it while
  // others already see themselves as its last owner and write in place). Each copy must end with
  // exactly its own writes, the original untouched. (Run under -fsanitize=thread for the ordering.)
  constexpr int kCopies = 8;
  constexpr int kSide = 4 * IntGrid::kTileSize;  // 4 x 4 tiles
  const auto initial = [](int x, int y) { return 1000 * x + y; };
  IntGrid original;
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) original.mutable_at({x, y}) = initial(x, y);
  }
  for (int round = 0; round < 20; ++round) {
    std::vector<IntGrid> copies(kCopies, original);
    std::vector<long long> sums(kCopies, 0);
    std::vector<std::thread> threads;
    for (int k = 0; k < kCopies; ++k) {
      threads.emplace_back([&, k] {
        IntGrid& grid = copies[static_cast<std::size_t>(k)];
        for (int t = 0; t < 16; ++t) {
          const int tile = (t + 2 * k + round) % 16;
          const int x0 = (tile % 4) * IntGrid::kTileSize;
          const int y0 = (tile / 4) * IntGrid::kTileSize;
          for (int y = 0; y < kSide; y += 7) sums[static_cast<std::size_t>(k)] += grid.at({(y * 3) % kSide, y});
          if ((k + t) % 2 == 0) {
            for (int y = y0; y < y0 + IntGrid::kTileSize; ++y) {
              for (int x = x0; x < x0 + IntGrid::kTileSize; ++x) grid.mutable_at({x, y}) += k + 1;
            }
          } else {
            for (int y = y0; y < y0 + IntGrid::kTileSize; ++y) {
              grid.update_ray({x0, y}, {x0 + IntGrid::kTileSize, y}, [k](int& cell) { cell += k + 1; });
            }
          }
        }
      });
    }
    for (std::thread& thread : threads) thread.join();
    for (int k = 0; k < kCopies; ++k) {
      const IntGrid& grid = copies[static_cast<std::size_t>(k)];
      int wrong = 0;
      for (int y = 0; y < kSide; ++y) {
        for (int x = 0; x < kSide; ++x) wrong += grid.at({x, y}) != initial(x, y) + k + 1 ? 1 : 0;
      }
      EXPECT_EQ(wrong, 0) << "copy " << k << ", round " << round;
      EXPECT_FALSE(grid.shares_tile_with(original, {0, 0}));
      EXPECT_EQ(grid.tile_count(), 16u);
    }
    int changed = 0;
    for (int y = 0; y < kSide; ++y) {
      for (int x = 0; x < kSide; ++x) changed += original.at({x, y}) != initial(x, y) ? 1 : 0;
    }
    ASSERT_EQ(changed, 0) << "round " << round;
  }
}

TEST(TiledGrid, TheLastOwnerOfATileWritesInPlace) {
  // The copy that un-shares a tile leaves the other grid its only owner, which then writes the
  // tile in place (the path TiledGrid::mutable_tile's acquire fence is on) without disturbing the copy.
  IntGrid original;
  original.mutable_at({0, 0}) = 1;
  const int* tile_before = &original.at({0, 0});
  IntGrid copy = original;
  copy.mutable_at({0, 0}) = 2;                    // copies the tile
  EXPECT_EQ(&original.mutable_at({0, 0}), tile_before);  // sole owner again: no copy
  original.mutable_at({0, 0}) = 3;
  EXPECT_EQ(copy.at({0, 0}), 2);
  EXPECT_EQ(original.at({0, 0}), 3);
}

}  // namespace
}  // namespace slam2d
