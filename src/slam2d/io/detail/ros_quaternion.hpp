// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The rotation of a ROS geometry_msgs/Quaternion as the planar readers need it: the z-y-x Euler
// angles (yaw for poses and transforms, roll and pitch for an IMU's attitude), and back. One home
// for the ROS 1 and the CDR decoders and encoders.

#include <algorithm>
#include <cmath>

namespace slam2d::detail {

struct RosQuaternion {
  double x = 0.0, y = 0.0, z = 0.0, w = 1.0;

  /// The rotation of z-y-x Euler angles: yaw about z, then pitch about y, then roll about x.
  static RosQuaternion from_euler(double roll, double pitch, double yaw) {
    const double cr = std::cos(0.5 * roll), sr = std::sin(0.5 * roll);
    const double cp = std::cos(0.5 * pitch), sp = std::sin(0.5 * pitch);
    const double cy = std::cos(0.5 * yaw), sy = std::sin(0.5 * yaw);
    return {sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy};
  }
  static RosQuaternion from_yaw(double yaw) { return from_euler(0.0, 0.0, yaw); }

  /// atan2(2(wz + xy), 1 - 2(y^2 + z^2)).
  double yaw() const { return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)); }
  double roll() const { return std::atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)); }
  double pitch() const { return std::asin(std::clamp(2.0 * (w * y - z * x), -1.0, 1.0)); }
};

/// Yaw of the quaternion (x, y, z, w).
inline double quaternion_yaw(double x, double y, double z, double w) { return RosQuaternion{x, y, z, w}.yaw(); }

}  // namespace slam2d::detail
