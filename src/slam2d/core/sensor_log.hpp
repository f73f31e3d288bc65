// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The format-neutral sensor log: what every log reader produces (io/carmen.hpp today) and what
// the simulator, the fault injector and every method consume. Scans with the odometry pose at
// each, odometry readings, true poses and IMU readings, each stamped, in the order the source gave them.

#include <cstddef>
#include <string>
#include <variant>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/odometry.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct LaserMessage {
  std::string type;   // the source's message type (CARMEN: "FLASER", "RLASER", "ROBOTLASER1", "RAWLASER1" .. "RAWLASER4")
  LaserScan scan;     // stamp (CARMEN: ipc_timestamp), angles, ranges, T_robot_sensor
  double field_of_view = 0.0;  // rad, as declared by the log (or the format's convention)
  SE2 laser_pose;     // the pose the source logged with the scan (CARMEN's "x y theta" triple; raw logs repeat odometry)
  SE2 odom_pose;      // the robot's odometry pose at the scan (T_odom_robot); absent in RAWLASER
  bool has_poses = true;  // false for RAWLASER, which carries no pose
  std::size_t line = 0;   // 1-based line in the file (record, for binary formats)
};

struct TruePoseMessage {
  double stamp = 0.0;  // s
  SE2 true_pose;
  SE2 odom_pose;
  std::size_t line = 0;
};

struct OdometryMessage {
  OdometryReading reading;
  std::size_t line = 0;
};

/// An inertial reading made planar: the attitude's roll and pitch (for levelling) and the yaw rate.
struct ImuReading {
  double stamp = 0.0;     // s
  double roll = 0.0;      // rad
  double pitch = 0.0;     // rad
  double yaw_rate = 0.0;  // rad/s, about the robot's z axis
};

struct ImuMessage {
  ImuReading reading;
  std::size_t line = 0;
};

/// One message of a sensor log, in the order the source gave it.
using SensorMessage = std::variant<LaserMessage, OdometryMessage, TruePoseMessage, ImuMessage>;

/// The stamp of any message.
double stamp_of(const SensorMessage& message);

}  // namespace slam2d
