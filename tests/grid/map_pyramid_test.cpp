// SPDX-License-Identifier: BSD-3-Clause
// The multi-resolution map of Kohlbrecher et al. 2011, Sec. IV-C: level k at resolution r 2^k,
// every level updated from the scans themselves (not downsampled from level 0).

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "slam2d/core/error.hpp"
#include "slam2d/grid/map_pyramid.hpp"

namespace slam2d {
namespace {

LaserScan wall_scan(double distance) {
  LaserScan scan;
  scan.angle_min = -std::numbers::pi / 4;
  scan.angle_increment = std::numbers::pi / 360;
  scan.range_max = 30.0;
  for (int i = 0; i <= 180; ++i) scan.ranges.push_back(distance / std::cos(scan.angle(static_cast<std::size_t>(i))));
  return scan;  // a straight wall at x = distance in front of the sensor
}

TEST(MapPyramid, LevelsDoubleTheResolution) {
  const MapPyramid pyramid({.levels = 4, .grid = {.resolution = 0.05}});
  ASSERT_EQ(pyramid.levels(), 4);
  EXPECT_DOUBLE_EQ(pyramid.resolution(0), 0.05);
  EXPECT_DOUBLE_EQ(pyramid.resolution(1), 0.1);
  EXPECT_DOUBLE_EQ(pyramid.resolution(2), 0.2);
  EXPECT_DOUBLE_EQ(pyramid.resolution(3), 0.4);
  EXPECT_THROW(pyramid.level(4), Error);
  EXPECT_THROW(pyramid.level(-1), Error);
  EXPECT_THROW(MapPyramid({.levels = 0, .grid = {}}), Error);
  EXPECT_THROW(MapPyramid({.levels = 17, .grid = {}}), Error);
}

TEST(MapPyramid, EveryLevelEqualsAGridUpdatedFromTheSameScans) {
  const MapPyramidConfig config{.levels = 3, .grid = {.resolution = 0.05}};
  MapPyramid pyramid(config);
  const SE2 poses[] = {SE2(0, 0, 0), SE2(0.3, 0.1, 0.05), SE2(0.6, 0.05, -0.1)};
  for (const SE2& pose : poses) pyramid.integrate_scan(wall_scan(3.0), pose);
  for (int k = 0; k < 3; ++k) {
    OccupancyGridConfig grid_config = config.grid;
    grid_config.resolution = 0.05 * (1 << k);
    OccupancyGrid reference(grid_config);
    for (const SE2& pose : poses) reference.integrate_scan(wall_scan(3.0), pose);
    const OccupancyGrid& level = pyramid.level(k);
    ASSERT_EQ(level.observed_box(), reference.observed_box()) << "level " << k;
    EXPECT_EQ(level.scan_count(), 3u);
    const CellBox box = level.observed_box();
    for (int y = box.min.y; y <= box.max.y; ++y) {
      for (int x = box.min.x; x <= box.max.x; ++x) {
        ASSERT_EQ(level.log_odds({x, y}), reference.log_odds({x, y}));
        ASSERT_EQ(level.is_known({x, y}), reference.is_known({x, y}));
      }
    }
  }
}

}  // namespace
}  // namespace slam2d
