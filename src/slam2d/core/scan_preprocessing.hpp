// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scan preprocessing for Hector SLAM (S. Kohlbrecher, O. von Stryk, J. Meyer, U. Klingauf, "A
// flexible and scalable SLAM system with full 3D motion estimation", SSRR 2011, Sec. III and
// IV-B): the end points used for matching, the projection of a tilted scan onto the horizontal
// plane from an IMU attitude, and the correction of the rotational motion distortion of a sweep.

#include <Eigen/Core>
#include <vector>

#include "slam2d/core/laser_scan.hpp"

namespace slam2d {

/// Robot-frame end points (m) of the beams with a reading in [min_range, min(scan.range_max,
/// max_range)): NaN, inf and no-return readings are dropped.
std::vector<Eigen::Vector2d> usable_end_points(const LaserScan& scan, double min_range, double max_range);

/// Roll and pitch of the laser's mounting platform, as an IMU reports them (rad). The scan plane
/// is the horizontal plane rotated by R = R_y(pitch) R_x(roll).
struct Attitude {
  double roll = 0.0;   // rad, about the x axis
  double pitch = 0.0;  // rad, about the y axis
};

/// Sec. III: the 3D end points R (x, y, 0) of a tilted scan, projected onto the horizontal plane
/// (their x and y). Points are in the frame of the tilted platform, (0, 0) at the rotation centre.
std::vector<Eigen::Vector2d> project_to_horizontal(const std::vector<Eigen::Vector2d>& points, const Attitude& attitude);

/// The scan seen from the levelled platform: each reading replaced by its horizontal length,
/// its bearing by the bearing of its projection. The projected bearings are no longer evenly
/// spaced, so this returns the end points; use it for matching.
std::vector<Eigen::Vector2d> horizontal_end_points(const LaserScan& scan, const Attitude& attitude, double min_range,
                                                   double max_range);

/// Rotational motion-distortion correction. A sweep whose beams are taken one after the other
/// over `sweep_duration` seconds (beam i at stamp + i sweep_duration / (n - 1)) while the robot
/// turns at `angular_rate` (rad/s, from an IMU or from odometry) sees beam i from a heading
/// rotated by angular_rate * t_i. Re-projecting every beam into the frame of the robot at
/// the scan's stamp (its first beam) adds that rotation to the beam's bearing; since t_i is linear
/// in i, the corrected bearings stay evenly spaced:
///   angle_min' = angle_min,  angle_increment' = angle_increment + angular_rate sweep_duration / (n - 1).
/// Exact for a pure rotation about the sensor's origin (a sensor mounted off the rotation axis
/// keeps a residual offset of |t_robot_sensor| * rotation). Translation during the sweep is not
/// corrected. Scans with fewer than 2 beams are returned unchanged.
LaserScan correct_rotational_distortion(const LaserScan& scan, double angular_rate, double sweep_duration);

}  // namespace slam2d
