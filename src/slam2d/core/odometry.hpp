// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Wheel odometry: the robot's dead-reckoned pose in the odometry frame.

#include <algorithm>

#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OdometryReading {
  double stamp = 0.0;  // s
  SE2 pose;            // T_odom_robot
  double tv = 0.0;     // m/s, translational velocity
  double rv = 0.0;     // rad/s, rotational velocity
};

/// Constant velocity: `last_motion` (made over last_dt) extrapolated over dt. The scale
/// dt / last_dt is clamped to [0.5, 2] (1 when either step is not positive), so that jittery or
/// out-of-order stamps cannot blow the extrapolation up (Intel has scans 1 ms apart).
inline SE2 constant_velocity_motion(const SE2& last_motion, double dt, double last_dt) {
  const double scale = dt > 0.0 && last_dt > 0.0 ? std::clamp(dt / last_dt, 0.5, 2.0) : 1.0;
  return SE2::exp(last_motion.log() * scale);
}

}  // namespace slam2d
