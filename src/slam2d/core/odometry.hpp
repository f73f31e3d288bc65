#pragma once
// Wheel odometry: the robot's dead-reckoned pose in the odometry frame.

#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OdometryReading {
  double stamp = 0.0;  // s
  SE2 pose;            // T_odom_robot
  double tv = 0.0;     // m/s, translational velocity
  double rv = 0.0;     // rad/s, rotational velocity
};

}  // namespace slam2d
