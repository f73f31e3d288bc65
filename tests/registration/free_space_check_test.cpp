// SPDX-License-Identifier: BSD-3-Clause
// The free-space check (registration/free_space_check.hpp): points on the map's walls agree,
// points on the free space it saw contradict, points where it saw nothing say nothing.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/registration/free_space_check.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {
namespace {

// A robot at the origin before a wall x = 2 m, seen by 101 beams over +-0.4 rad, ten times.
OccupancyGrid wall_map() {
  LaserScan scan;
  scan.angle_min = -0.4;
  scan.angle_increment = 0.008;
  scan.range_min = 0.1;
  scan.range_max = 10.0;
  for (int i = 0; i <= 100; ++i) scan.ranges.push_back(2.0 / std::cos(scan.angle(static_cast<std::size_t>(i))));
  OccupancyGrid grid(OccupancyGridConfig{.resolution = 0.05});
  for (int k = 0; k < 10; ++k) grid.integrate_scan(scan, SE2());
  return grid;
}

TEST(FreeSpaceCheck, WallsAgreeFreeSpaceContradictsTheUnseenSaysNothing) {
  const OccupancyGrid grid = wall_map();
  const PointCloud2 wall_points = occupied_points(grid.to_occupancy_map(), 65);
  const KdTree2 walls(wall_points.points);
  ASSERT_GT(walls.size(), 10u);
  // On the wall, and 0.1 m off it: agree.
  const std::vector<Point2> on_wall{{2.0, 0.0}, {2.0, 0.5}, {1.9, -0.3}};
  FreeSpaceCheck check = check_free_space(grid, walls, on_wall, 0.2);
  EXPECT_EQ(check.seen, 3u);
  EXPECT_EQ(check.contradicting, 0u);
  EXPECT_FALSE(check.contradicted(0.15));
  // The same wall moved 1 m towards the robot: in the free space it saw.
  const std::vector<Point2> moved{{1.0, 0.0}, {1.0, 0.3}, {1.0, -0.3}};
  check = check_free_space(grid, walls, moved, 0.2);
  EXPECT_EQ(check.seen, 3u);
  EXPECT_EQ(check.contradicting, 3u);
  EXPECT_TRUE(check.contradicted(0.15));
  // Behind the wall and behind the robot it saw nothing: nothing is seen, which refutes nothing
  // and confirms nothing (a placement with no overlap is refused).
  const std::vector<Point2> unseen{{3.0, 0.0}, {-1.0, 0.0}};
  check = check_free_space(grid, walls, unseen, 0.2);
  EXPECT_EQ(check.seen, 0u);
  EXPECT_TRUE(check.contradicted(0.15));
  // One point in five on free space: 20 % against a 15 % share.
  const std::vector<Point2> mixed{{2.0, 0.0}, {2.0, 0.2}, {2.0, -0.2}, {2.0, 0.4}, {1.0, 0.0}};
  check = check_free_space(grid, walls, mixed, 0.2);
  EXPECT_EQ(check.contradicting, 1u);
  EXPECT_TRUE(check.contradicted(0.15));
  EXPECT_FALSE(check.contradicted(0.25));
}

}  // namespace
}  // namespace slam2d
