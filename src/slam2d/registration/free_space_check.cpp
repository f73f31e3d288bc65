// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/free_space_check.hpp"

#include "slam2d/core/occupancy_map.hpp"

namespace slam2d {

PointCloud2 wall_points(const OccupancyGrid& map) {
  constexpr int kOccupied = 65;  // %, as map_saver's
  return occupied_points(map.to_occupancy_map(), kOccupied);
}

FreeSpaceCheck check_free_space(const OccupancyGrid& map, const KdTree2& walls, std::span<const Point2> points,
                                double distance) {
  constexpr double kFree = 0.25;  // P(occupied) below which a cell was seen free
  FreeSpaceCheck check;
  for (const Point2& p : points) {
    const Neighbor nearest = walls.nearest(p);
    if (nearest.index < walls.size() && nearest.squared_distance <= distance * distance) {
      ++check.seen;
    } else if (map.probability(p) < kFree) {
      ++check.seen;
      ++check.contradicting;
    }
  }
  return check;
}

}  // namespace slam2d
