// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// LaserScan: one sweep of a planar range finder, in the shape of ROS's sensor_msgs/LaserScan.

#include <cstddef>
#include <vector>

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct LaserScan {
  double stamp = 0.0;            // s
  double angle_min = 0.0;        // rad, bearing of the first beam in the sensor frame
  double angle_increment = 0.0;  // rad, between consecutive beams
  double range_min = 0.0;        // m, readings below are invalid
  double range_max = 0.0;        // m, readings at or above are "no return"
  std::vector<double> ranges;       // m, one per beam
  std::vector<double> intensities;  // empty, or one per beam
  SE2 T_robot_sensor;               // the sensor's mounting pose on the robot

  std::size_t size() const { return ranges.size(); }
  double angle(std::size_t beam) const { return angle_min + static_cast<double>(beam) * angle_increment; }
  double angle_max() const { return ranges.empty() ? angle_min : angle(ranges.size() - 1); }
  /// A usable return: finite and in [range_min, range_max).
  bool is_valid(std::size_t beam) const;
};

enum class ScanFrame { kSensor, kRobot };

/// A scan's end points, and what was left out.
struct ScanPoints {
  PointCloud2 cloud;
  std::vector<std::size_t> beam_indices;  // the beam each point came from, ascending
  std::size_t dropped_nonfinite = 0;      // NaN or inf readings
  std::size_t dropped_out_of_range = 0;   // below range_min or at/above range_max
};

/// End points of the valid beams, in the sensor frame or (applying T_robot_sensor) the robot frame.
ScanPoints to_point_cloud(const LaserScan& scan, ScanFrame frame = ScanFrame::kRobot);

}  // namespace slam2d
