// SPDX-License-Identifier: BSD-3-Clause
// OccupancyGrid: ray casting updates, no-return beams, invalid readings, copy-on-write, export.

#include "slam2d/grid/occupancy_grid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/grid/ray_casting.hpp"

namespace slam2d {
namespace {

constexpr double kP = 1e-6;  // float log-odds: probabilities agree to ~1e-7

/// A scan with the given (bearing, range) beams; the bearings must be evenly spaced.
LaserScan scan_of(const std::vector<std::pair<double, double>>& beams, double range_max = 20.0) {
  LaserScan scan;
  scan.range_max = range_max;
  scan.angle_min = beams.empty() ? 0.0 : beams.front().first;
  scan.angle_increment = beams.size() > 1 ? beams[1].first - beams[0].first : 0.0;
  for (const auto& beam : beams) scan.ranges.push_back(beam.second);
  return scan;
}

LaserScan single_beam(double bearing, double range, double range_max = 20.0) { return scan_of({{bearing, range}}, range_max); }

std::vector<CellIndex> known_cells(const OccupancyGrid& grid, int radius) {
  std::vector<CellIndex> cells;
  for (int y = -radius; y <= radius; ++y) {
    for (int x = -radius; x <= radius; ++x) {
      if (grid.is_known({x, y})) cells.push_back({x, y});
    }
  }
  return cells;
}

OccupancyGridConfig metre_cells() { return OccupancyGridConfig{.resolution = 1.0}; }

TEST(OccupancyGrid, SingleBeamMarksExactlyTheRayCells) {
  OccupancyGrid grid(metre_cells());
  // Sensor at the centre of cell (0, 0) (robot at x = 0.3 with the sensor 0.2 m ahead), beam
  // towards the centre of cell (5, 2): Bresenham offsets round(2 i / 5) = 0 0 1 1 2.
  LaserScan scan = single_beam(std::atan2(2.0, 5.0), std::sqrt(29.0));
  scan.T_robot_sensor = SE2(0.2, 0.0, 0.0);
  grid.integrate_scan(scan, SE2(0.3, 0.5, 0.0));
  const std::vector<CellIndex> expected{{0, 0}, {1, 0}, {2, 1}, {3, 1}, {4, 2}, {5, 2}};
  std::vector<CellIndex> known = known_cells(grid, 10);
  std::sort(known.begin(), known.end(), [](CellIndex a, CellIndex b) { return a.x < b.x; });
  EXPECT_EQ(known, expected);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(grid.probability(expected[static_cast<std::size_t>(i)]), 0.4, kP);
  EXPECT_NEAR(grid.probability(CellIndex{5, 2}), 0.7, kP);
  EXPECT_NEAR(grid.log_odds({5, 2}), std::log(0.7 / 0.3), 1e-6);
  EXPECT_EQ(grid.probability(CellIndex{6, 2}), 0.5);  // unknown
  EXPECT_EQ(grid.log_odds({6, 2}), 0.0);
  EXPECT_NEAR(grid.probability(Eigen::Vector2d(5.9, 2.1)), 0.7, kP);
  EXPECT_EQ(grid.probability(Eigen::Vector2d(std::nan(""), 2.1)), 0.5);
  EXPECT_EQ(grid.probability(Eigen::Vector2d(1e300, 0.0)), 0.5);
  EXPECT_EQ(grid.observed_box(), (CellBox{{0, 0}, {5, 2}}));
  EXPECT_EQ(grid.scan_count(), 1u);
}

TEST(OccupancyGrid, RepeatedScansAccumulateAndClamp) {
  OccupancyGrid grid(metre_cells());
  const LaserScan scan = single_beam(0.0, 3.0);
  grid.integrate_scan(scan, SE2(0.5, 0.5, 0.0));
  grid.integrate_scan(scan, SE2(0.5, 0.5, 0.0));
  // Two updates: l = 2 logit(p), p = p^2 / (p^2 + (1 - p)^2).
  EXPECT_NEAR(grid.probability(CellIndex{3, 0}), 0.49 / (0.49 + 0.09), kP);
  EXPECT_NEAR(grid.probability(CellIndex{1, 0}), 0.16 / (0.16 + 0.36), kP);
  for (int i = 0; i < 30; ++i) grid.integrate_scan(scan, SE2(0.5, 0.5, 0.0));
  EXPECT_NEAR(grid.probability(CellIndex{3, 0}), 0.97, kP);  // probability_max
  EXPECT_NEAR(grid.probability(CellIndex{1, 0}), 0.12, kP);  // probability_min
}

TEST(OccupancyGrid, NoReturnBeamsClearButNeverMark) {
  OccupancyGrid grid(OccupancyGridConfig{.resolution = 1.0, .max_clear_range = 3.0});
  // range_max 4: readings of 10 and exactly 4 are both "no return"; they clear up to
  // min(reading, 3 m) = 3 m, i.e. cells 0..2 (the cell at 3 m is the end cell: not updated).
  grid.integrate_scan(single_beam(0.0, 10.0, 4.0), SE2(0.5, 0.5, 0.0));
  grid.integrate_scan(single_beam(std::numbers::pi, 4.0, 4.0), SE2(0.5, 0.5, 0.0));
  for (int x = 0; x <= 2; ++x) EXPECT_TRUE(grid.is_known({x, 0})) << x;
  EXPECT_FALSE(grid.is_known({3, 0}));
  for (int x = -2; x <= -1; ++x) EXPECT_NEAR(grid.probability(CellIndex{x, 0}), 0.4, kP) << x;
  EXPECT_FALSE(grid.is_known({-3, 0}));
  for (const CellIndex cell : known_cells(grid, 10)) EXPECT_LT(grid.probability(cell), 0.5);
  // A no-return reading shorter than max_clear_range clears only up to the reading.
  OccupancyGrid short_grid(OccupancyGridConfig{.resolution = 1.0, .max_clear_range = 30.0});
  short_grid.integrate_scan(single_beam(0.0, 6.0, 5.0), SE2(0.5, 0.5, 0.0));
  EXPECT_EQ(known_cells(short_grid, 20).size(), 6u);  // cells 0..5; the end cell (6, 0) untouched
  EXPECT_FALSE(short_grid.is_known({6, 0}));
}

TEST(OccupancyGrid, ReturnsBeyondConfiguredMaxRangeAreNoReturnBeams) {
  OccupancyGrid grid(OccupancyGridConfig{.resolution = 1.0, .max_clear_range = 2.0, .max_range = 5.0});
  grid.integrate_scan(single_beam(0.0, 7.0, 80.0), SE2(0.5, 0.5, 0.0));
  EXPECT_EQ(known_cells(grid, 10).size(), 2u);
  EXPECT_NEAR(grid.probability(CellIndex{1, 0}), 0.4, kP);
}

TEST(OccupancyGrid, InvalidReadingsAreIgnored) {
  OccupancyGrid grid(metre_cells());
  LaserScan scan = scan_of({{0.0, std::numeric_limits<double>::quiet_NaN()},
                            {0.5, std::numeric_limits<double>::infinity()},
                            {1.0, -std::numeric_limits<double>::infinity()},
                            {1.5, 0.05},   // below range_min
                            {2.0, -3.0},   // negative
                            {2.5, 0.0}});  // zero
  scan.range_min = 0.1;
  grid.integrate_scan(scan, SE2(0.5, 0.5, 0.0));
  EXPECT_TRUE(grid.observed_box().empty());
  EXPECT_EQ(grid.cells().tile_count(), 0u);
  EXPECT_EQ(grid.scan_count(), 0u);
  // Mixed with one valid beam, only that beam counts.
  scan.ranges[0] = 2.0;
  grid.integrate_scan(scan, SE2(0.5, 0.5, 0.0));
  EXPECT_EQ(known_cells(grid, 10).size(), 3u);
}

TEST(OccupancyGrid, NonFiniteOrFarPosesAreErrors) {
  OccupancyGrid grid;
  const LaserScan scan = single_beam(0.0, 1.0);
  EXPECT_THROW(grid.integrate_scan(scan, SE2(std::nan(""), 0.0, 0.0)), Error);
  EXPECT_THROW(grid.integrate_scan(scan, SE2(1e9, 0.0, 0.0)), Error);
  LaserScan bad_angles = scan;
  bad_angles.angle_min = std::numeric_limits<double>::infinity();
  EXPECT_THROW(grid.integrate_scan(bad_angles, SE2()), Error);
  EXPECT_EQ(grid.cells().tile_count(), 0u);
}

TEST(OccupancyGrid, InvalidConfigurationsAreErrors) {
  EXPECT_THROW(OccupancyGrid(OccupancyGridConfig{.resolution = 0.0}), Error);
  EXPECT_THROW(OccupancyGrid(OccupancyGridConfig{.probability_hit = 0.4}), Error);
  EXPECT_THROW(OccupancyGrid(OccupancyGridConfig{.probability_miss = 0.6}), Error);
  EXPECT_THROW(OccupancyGrid(OccupancyGridConfig{.probability_max = 1.0}), Error);
  EXPECT_THROW(OccupancyGrid(OccupancyGridConfig{.max_clear_range = std::nan("")}), Error);
}

TEST(OccupancyGrid, HitWinsAndEachCellIsUpdatedOncePerScan) {
  OccupancyGrid grid(metre_cells());
  // Beam 0 ends in cell (2, 0); beam 1 (same bearing) passes through it to (5, 0).
  grid.integrate_scan(scan_of({{0.0, 2.2}, {0.0, 5.2}}), SE2(0.5, 0.5, 0.0));
  EXPECT_NEAR(grid.probability(CellIndex{2, 0}), 0.7, kP);  // the hit only
  EXPECT_NEAR(grid.probability(CellIndex{1, 0}), 0.4, kP);  // one miss, though two rays passed
  EXPECT_NEAR(grid.probability(CellIndex{3, 0}), 0.4, kP);
  EXPECT_NEAR(grid.probability(CellIndex{5, 0}), 0.7, kP);
  // A fan of 181 beams: the sensor cell lies on every ray, yet gets a single miss.
  std::vector<std::pair<double, double>> fan;
  for (int i = 0; i <= 180; ++i) fan.emplace_back(i * std::numbers::pi / 180.0, 4.0);
  OccupancyGrid fan_grid(metre_cells());
  fan_grid.integrate_scan(scan_of(fan), SE2(0.5, 0.5, 0.0));
  EXPECT_NEAR(fan_grid.probability(CellIndex{0, 0}), 0.4, kP);
  EXPECT_NEAR(fan_grid.probability(CellIndex{0, 2}), 0.4, kP);
  EXPECT_NEAR(fan_grid.probability(CellIndex{0, 4}), 0.7, kP);
}

// A wall along y = 1.025 m (the middle of cell row 20) seen from the origin by beams 1 degree apart
// from `first` to `last` degrees: far out its returns lie metres apart.
LaserScan grazing_wall(int first, int last, double wall_y = 1.025) {
  std::vector<std::pair<double, double>> beams;
  for (int degrees = first; degrees <= last; ++degrees) {
    const double bearing = degrees * std::numbers::pi / 180.0;
    beams.emplace_back(bearing, wall_y / std::sin(bearing));
  }
  return scan_of(beams, 80.0);
}

// Every cell of the wall's row between its farthest and nearest return: held by the surface
// hits, unknown or free without them.
TEST(OccupancyGrid, AGrazingWallIsAWallNotDotsABeamApart) {
  const OccupancyGridConfig dots{.resolution = 0.05};
  OccupancyGridConfig walls = dots;
  walls.surface_hit_weight = 0.5;
  const LaserScan scan = grazing_wall(4, 40);  // returns 14.7 m to 1.2 m out, 3.6 m to 4 cm apart
  OccupancyGrid with_dots(dots);
  OccupancyGrid with_walls(walls);
  with_dots.integrate_scan(scan, SE2());
  with_walls.integrate_scan(scan, SE2());
  const int near = static_cast<int>(std::floor(1.025 / std::tan(39.0 * std::numbers::pi / 180.0) / 0.05));
  // From the second-farthest return to the second-nearest: a surface's last step is not filled.
  const int far = static_cast<int>(std::floor(1.025 / std::tan(5.0 * std::numbers::pi / 180.0) / 0.05));
  int dots_occupied = 0;
  for (int x = near; x <= far; ++x) {
    const CellIndex cell{x, 20};
    if (with_dots.probability(cell) > 0.5) ++dots_occupied;
    // A hit (0.7), or half a hit's log-odds between two returns.
    EXPECT_GE(with_walls.probability(cell), probability_from_log_odds(0.5 * logit(0.7)) - kP) << "x " << x;
  }
  EXPECT_LT(dots_occupied, (far - near + 1) / 4) << "the returns alone should leave most of the row open";
  // Off the wall's row nothing is marked.
  for (int x = near; x <= far; ++x) EXPECT_LE(with_walls.probability(CellIndex{x, 19}), 0.5);
}

// A depth edge (a near wall's end, the far wall behind it) and mixed pixels (beams alternating
// between the two) are not surfaces: nothing is marked between their returns.
TEST(OccupancyGrid, NoSurfaceAcrossADepthEdgeOrMixedPixels) {
  OccupancyGridConfig config{.resolution = 0.05};
  config.surface_hit_weight = 0.5;
  std::vector<std::pair<double, double>> edge;
  std::vector<std::pair<double, double>> mixed;
  for (int degrees = 5; degrees <= 40; ++degrees) {
    const double bearing = degrees * std::numbers::pi / 180.0;
    const double near = 1.025 / std::sin(bearing);
    const double far = 3.025 / std::sin(bearing);
    edge.emplace_back(bearing, degrees < 20 ? far : near);
    mixed.emplace_back(bearing, degrees % 2 == 0 ? far : near);
  }
  // The edge: no cell between the two walls' rows is marked.
  OccupancyGrid edge_grid(config);
  edge_grid.integrate_scan(scan_of(edge, 80.0), SE2());
  for (int y = 21; y < 60; ++y) {
    for (int x = 0; x <= 800; ++x) EXPECT_LE(edge_grid.probability(CellIndex{x, y}), 0.5) << x << " " << y;
  }
  // The mixed pixels: neighbouring returns are never on one wall, so the map is the returns' alone.
  OccupancyGrid mixed_grid(config);
  OccupancyGrid returns_only(OccupancyGridConfig{.resolution = 0.05});
  mixed_grid.integrate_scan(scan_of(mixed, 80.0), SE2());
  returns_only.integrate_scan(scan_of(mixed, 80.0), SE2());
  for (int y = 0; y <= 70; ++y) {
    for (int x = 0; x <= 800; ++x) {
      EXPECT_EQ(mixed_grid.probability(CellIndex{x, y}), returns_only.probability(CellIndex{x, y})) << x << " " << y;
    }
  }
}

TEST(OccupancyGrid, GrowsInEveryDirection) {
  OccupancyGrid grid;  // 5 cm
  std::vector<std::pair<double, double>> beams;
  for (int i = 0; i < 4; ++i) beams.emplace_back(i * std::numbers::pi / 2.0, 10.0);
  const SE2 pose(-7.02, -3.02, 0.0);  // away from cell borders: exact cells below
  grid.integrate_scan(scan_of(beams), pose);
  const Eigen::Vector2d ends[] = {{2.98, -3.02}, {-7.02, 6.98}, {-17.02, -3.02}, {-7.02, -13.02}};
  for (const Eigen::Vector2d& end : ends) {
    EXPECT_NEAR(grid.probability(end), 0.7, kP) << end.transpose();
    const Eigen::Vector2d mid = 0.5 * (end + pose.translation());
    EXPECT_NEAR(grid.probability(mid), 0.4, kP) << mid.transpose();
  }
  // floor(-17.02 / 0.05) = -341, floor(-13.02 / 0.05) = -261, floor(2.98 / 0.05) = 59, floor(6.98 / 0.05) = 139.
  EXPECT_EQ(grid.observed_box(), (CellBox{{-341, -261}, {59, 139}}));
}

TEST(OccupancyGrid, CopiesShareTilesUntilWritten) {
  OccupancyGrid original;
  original.integrate_scan(single_beam(0.0, 2.0), SE2(0.01, 0.01, 0.0));    // tiles around (0, 0)
  original.integrate_scan(single_beam(0.0, 2.0), SE2(-20.0, 15.0, 0.0));  // far away
  OccupancyGrid copy = original;
  copy.integrate_scan(single_beam(std::numbers::pi / 2, 1.0), SE2(0.01, 0.01, 0.0));
  EXPECT_NEAR(copy.probability(Eigen::Vector2d(0.02, 1.02)), 0.7, kP);
  EXPECT_FALSE(original.is_known(original.geometry().cell_of({0.02, 1.02})));  // original unchanged
  EXPECT_NEAR(original.probability(Eigen::Vector2d(0.02, 0.02)), 0.4, kP);
  EXPECT_NEAR(copy.probability(Eigen::Vector2d(0.02, 0.02)), 0.4 * 0.4 / (0.16 + 0.36), kP);
  const CellIndex far = original.geometry().cell_of({-19.0, 15.0});
  EXPECT_TRUE(copy.cells().shares_tile_with(original.cells(), far));
  EXPECT_FALSE(copy.cells().shares_tile_with(original.cells(), {0, 0}));
}

TEST(OccupancyGrid, ToOccupancyMapCropsWithAOneCellMargin) {
  OccupancyGrid grid(OccupancyGridConfig{.resolution = 0.5});
  grid.integrate_scan(single_beam(0.0, 2.6), SE2(-1.2, 3.1, 0.0));  // sensor cell (-3, 6), end (2.6 - 1.2 = 1.4) cell 2
  const OccupancyMap map = grid.to_occupancy_map();
  EXPECT_EQ(map.resolution, 0.5);
  EXPECT_EQ(map.width, 6 + 2);   // cells -3..2 plus margins
  EXPECT_EQ(map.height, 1 + 2);
  EXPECT_EQ(map.origin.x(), -2.0);  // corner of cell -4
  EXPECT_EQ(map.origin.y(), 2.5);   // corner of cell 5
  EXPECT_EQ(map.origin.theta(), 0.0);
  const std::vector<std::int8_t> expected{-1, -1, -1, -1, -1, -1, -1, -1,  //
                                          -1, 40, 40, 40, 40, 40, 70, -1,  //
                                          -1, -1, -1, -1, -1, -1, -1, -1};
  EXPECT_EQ(map.cells, expected);
  // The map's cells line up with the grid's: the centre of map cell (6, 1) is in grid cell (2, 6).
  EXPECT_EQ(grid.geometry().cell_of(map.cell_center(6, 1)), (CellIndex{2, 6}));
  EXPECT_EQ(OccupancyGrid().to_occupancy_map().cells.size(), 0u);
}

TEST(OccupancyGrid, MemoryFollowsTheExploredArea) {
  OccupancyGrid grid;
  const std::size_t empty = grid.memory_bytes();
  grid.integrate_scan(single_beam(0.0, 1.0), SE2(0.01, 0.01, 0.0));
  const std::size_t one_tile = grid.memory_bytes();
  EXPECT_EQ(grid.cells().tile_count(), 1u);
  EXPECT_GE(one_tile - empty, sizeof(TiledGrid<OccupancyCell>::Tile));
  grid.integrate_scan(single_beam(0.0, 1.0), SE2(50.0, 0.01, 0.0));  // far away: one more tile
  EXPECT_EQ(grid.cells().tile_count(), 2u);
  EXPECT_LT(grid.memory_bytes(), 2 * one_tile + 64 * sizeof(void*) * 2);
}

}  // namespace
}  // namespace slam2d
