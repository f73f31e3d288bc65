// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/scan_preprocessing.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace slam2d {

namespace {

bool usable(double range, double min_range, double limit) {
  return std::isfinite(range) && range >= min_range && range < limit && range > 0.0;
}

}  // namespace

std::vector<Eigen::Vector2d> usable_end_points(const LaserScan& scan, double min_range, double max_range) {
  const double limit = std::min(scan.range_max, max_range);
  const double low = std::max(min_range, scan.range_min);
  const Eigen::Matrix2d R = scan.T_robot_sensor.rotation();
  const Eigen::Vector2d& t = scan.T_robot_sensor.translation();
  std::vector<Eigen::Vector2d> points;
  points.reserve(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double range = scan.ranges[i];
    if (!usable(range, low, limit)) continue;
    const double angle = scan.angle(i);
    points.push_back(t + R * Eigen::Vector2d(range * std::cos(angle), range * std::sin(angle)));
  }
  return points;
}

std::vector<Eigen::Vector2d> project_to_horizontal(const std::vector<Eigen::Vector2d>& points, const Attitude& attitude) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(attitude.pitch, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(attitude.roll, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Matrix<double, 2, 2> R_xy = R.topLeftCorner<2, 2>();  // (x, y) of R (p_x, p_y, 0)
  std::vector<Eigen::Vector2d> projected;
  projected.reserve(points.size());
  for (const Eigen::Vector2d& p : points) projected.push_back(R_xy * p);
  return projected;
}

std::vector<Eigen::Vector2d> horizontal_end_points(const LaserScan& scan, const Attitude& attitude, double min_range,
                                                   double max_range) {
  return project_to_horizontal(usable_end_points(scan, min_range, max_range), attitude);
}

LaserScan correct_rotational_distortion(const LaserScan& scan, double angular_rate, double sweep_duration) {
  LaserScan corrected = scan;
  if (scan.size() < 2 || !std::isfinite(angular_rate) || !std::isfinite(sweep_duration)) return corrected;
  const double beam_interval = sweep_duration / static_cast<double>(scan.size() - 1);  // s between beams
  corrected.angle_increment = scan.angle_increment + angular_rate * beam_interval;
  return corrected;
}

}  // namespace slam2d
