// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Whether a map contradicts points placed in it: a relocalization or a loop closure puts one map
// (its walls' points) into another, and a scan that fits a wrong place (an alias a few doors along
// a corridor, a room's twin) fits it with its own few metres of wall; the walls beyond, seen from the
// other places of the moved map, then cross the other map's free space. Hector's search after a gap
// and graph SLAM's large closures refuse a placement this check rejects.

#include <cstddef>
#include <span>

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {

struct FreeSpaceCheck {
  std::size_t seen = 0;           // points that land on a wall of the map or on a cell it saw free
  std::size_t contradicting = 0;  // ... on a cell it saw free, no wall within the distance
  /// More than `max_share` of the points seen contradict it, or none is seen.
  bool contradicted(double max_share) const {
    return seen == 0 || static_cast<double>(contradicting) > max_share * static_cast<double>(seen);
  }
};

/// A map's walls: the centres of its cells at least 65 % occupied (the written map's threshold).
PointCloud2 wall_points(const OccupancyGrid& map);

/// `points` (in the map's frame) against the map: a point within `distance` of one of its walls
/// (`walls`, its occupied cells' centres, indexed) agrees; one on a cell it saw free (P(occupied)
/// below 0.25) with no wall that near contradicts; unknown cells say nothing.
FreeSpaceCheck check_free_space(const OccupancyGrid& map, const KdTree2& walls, std::span<const Point2> points,
                                double distance);

}  // namespace slam2d
