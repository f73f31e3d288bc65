// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/laser_scan.hpp"

#include <cmath>

namespace slam2d {

bool LaserScan::is_valid(std::size_t beam) const {
  const double r = ranges[beam];
  return std::isfinite(r) && r >= range_min && r < range_max;
}

ScanPoints to_point_cloud(const LaserScan& scan, ScanFrame frame) {
  ScanPoints result;
  result.cloud.points.reserve(scan.size());
  result.beam_indices.reserve(scan.size());
  const SE2 T = frame == ScanFrame::kRobot ? scan.T_robot_sensor : SE2();
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double r = scan.ranges[i];
    if (!std::isfinite(r)) {
      ++result.dropped_nonfinite;
      continue;
    }
    if (r < scan.range_min || r >= scan.range_max) {
      ++result.dropped_out_of_range;
      continue;
    }
    const double a = scan.angle(i);
    result.cloud.points.push_back(T.act(Point2(r * std::cos(a), r * std::sin(a))));
    result.beam_indices.push_back(i);
  }
  return result;
}

}  // namespace slam2d
