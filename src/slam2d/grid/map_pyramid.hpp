// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Multi-resolution occupancy maps: S. Kohlbrecher et al., "A flexible and scalable SLAM system
// with full 3D motion estimation", SSRR 2011, Sec. IV-C. Level k has resolution r 2^k; every level
// is a separate OccupancyGrid updated from the same scans (not a downsampled copy of level 0), so
// coarse levels stay consistent with the fine one without any resampling step.

#include <cstddef>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/occupancy_grid.hpp"

namespace slam2d {

struct MapPyramidConfig {
  int levels = 3;
  OccupancyGridConfig grid;
};

template <typename Fields>
void describe(Fields& f, MapPyramidConfig& c) {
  f.number("levels", c.levels, "1", between(1, 16), "number of maps");
  f.section("grid", c.grid, "of level 0; level k uses resolution grid.resolution * 2^k");
}

class MapPyramid {
 public:
  /// Throws Error for levels outside [1, 16] or an invalid grid configuration.
  explicit MapPyramid(const MapPyramidConfig& config = {});

  /// Integrates the scan into every level (OccupancyGrid::integrate_scan).
  void integrate_scan(const LaserScan& scan, const SE2& T_map_robot);

  int levels() const { return static_cast<int>(grids_.size()); }
  /// Level k (0 is the finest). Throws Error for k outside [0, levels()).
  const OccupancyGrid& level(int k) const;
  double resolution(int k) const { return level(k).geometry().resolution; }
  std::size_t memory_bytes() const;
  const MapPyramidConfig& config() const { return config_; }

 private:
  MapPyramidConfig config_;
  std::vector<OccupancyGrid> grids_;
};

}  // namespace slam2d
