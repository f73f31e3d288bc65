// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Simulated scan pairs with a known relative pose, for every matcher's tests: two scans of a
// world taken from T_world_target and T_world_source = T_world_target * T_target_source, both in
// their sensor frames (the sensor at the robot origin), with Gaussian range noise.

#include <cstdint>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/sim/world.hpp"

namespace slam2d::testing {

struct ScanPairOptions {
  SE2 T_world_target{6.5, 2.0, 0.3};  // in the office, room S1 (corners, a door, furniture, a pillar): well constrained
  SE2 T_target_source{0.15, -0.05, 0.05};
  int beams = 180;
  double field_of_view = 3.14159265358979323846;  // rad
  double range_max = 30.0;                         // m
  double range_sigma = 0.01;                       // m
  double dropout_probability = 0.0;
  std::uint64_t seed = 1;
};

struct ScanPair {
  LaserScan target_scan;
  LaserScan source_scan;
  PointCloud2 target;  // end points of the valid beams, sensor frame, beam order
  PointCloud2 source;
  SE2 T_target_source;  // the truth
};

ScanPair make_scan_pair(const World& world, const ScanPairOptions& options = {});

/// The office of the simulator (make_world("office")).
const World& office_world();
/// A straight corridor 2 m wide and 200 m long with plain walls: nothing fixes the position
/// along it within a 30 m range. The robot stands at (0, 0) with the axis along x.
const World& corridor_world();
/// A circular room of radius 5 m centred at (0, 0), as 360 wall segments: nothing fixes the
/// heading at its centre.
const World& circular_room_world();
/// A 8 m x 6 m rectangular room with a pillar and a desk, centred at (0, 0): well constrained.
const World& room_world();

}  // namespace slam2d::testing
