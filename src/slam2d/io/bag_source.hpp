// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The contract between a bag container reader (ROS 1 bag v2.0, MCAP, rosbag2 sqlite3) and the
// one assembly that turns any bag into the format-neutral sensor log (core/sensor_log.hpp).
//
// A container reader knows its file format and the wire encoding of its messages (ROS 1
// serialization or CDR); it decodes the few message types slam2d needs into the plain structs
// below and hands them over in the bag's order (each reader says which: ROS 1 in the recording
// order of the file, MCAP and rosbag2 in receive-time order, as ROS 2 writes them). Everything that
// does not depend on the format (which topic is the laser, the laser's mounting from /tf_static,
// the odometry pose at each scan, "no return" readings) lives once, in the assembly.

#include <cstddef>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/odometry.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/sensor_log.hpp"

namespace slam2d {

/// One topic (ROS 1: connection topic; MCAP: channel; rosbag2: topics row) of a bag.
struct BagTopic {
  std::string name = {};        // "/scan"
  std::string type = {};        // as the bag spells it: "sensor_msgs/LaserScan" (ROS 1) or "sensor_msgs/msg/LaserScan"
  std::size_t count = 0;   // messages on it
  double first_stamp = 0.0;  // s, receive time of its first and last message (0 when count is 0)
  double last_stamp = 0.0;
};

/// sensor_msgs/LaserScan. `scan` holds header.stamp, the message's angles and limits (as double),
/// every range as published (NaN, +-inf, values outside [range_min, range_max] are kept: the
/// assembly and LaserScan::is_valid treat them as "no return"); T_robot_sensor is identity.
struct DecodedScan {
  std::string frame_id = {};
  LaserScan scan = {};
};

/// nav_msgs/Odometry: header.stamp, the planar pose (x, y, yaw of the quaternion), twist.linear.x
/// and twist.angular.z.
struct DecodedOdometry {
  std::string frame_id = {};        // "odom"
  std::string child_frame_id = {};  // "base_link"
  OdometryReading reading = {};
};

/// One geometry_msgs/TransformStamped, made planar (x, y, yaw).
struct DecodedTransform {
  double stamp = 0.0;  // s, header.stamp
  std::string parent = {};  // header.frame_id
  std::string child = {};   // child_frame_id
  SE2 T_parent_child = {};
};

/// tf2_msgs/TFMessage, on /tf or /tf_static.
struct DecodedTransforms {
  bool is_static = false;  // the topic is /tf_static
  std::vector<DecodedTransform> transforms = {};
};

/// sensor_msgs/Imu: header.stamp, the attitude's roll and pitch, the yaw rate (angular_velocity.z).
struct DecodedImu {
  std::string frame_id = {};
  ImuReading reading = {};
};

using DecodedMessage = std::variant<DecodedScan, DecodedOdometry, DecodedTransforms, DecodedImu>;

/// One decoded message with where it came from.
struct DecodedRecord {
  std::string topic = {};
  double receive_time = 0.0;  // s: ROS 1 record time, MCAP log_time, rosbag2 timestamp
  std::size_t index = 0;      // its position in the file's own order (for messages: "record N")
  DecodedMessage message = {};
};

/// A container reader: the bag's topics, and its messages of the wanted topics decoded, in the
/// bag's order (above). Errors are Error("PATH: message") (a truncated chunk, a wrong CRC, an unknown
/// compression, a message running past its record), never a crash; sizes read from the file are
/// checked before anything is allocated.
class BagSource {
 public:
  virtual ~BagSource() = default;
  virtual const std::string& path() const = 0;
  /// Every topic of the bag, with its type and count (from the index or summary when the file has
  /// one, else from a first pass).
  virtual const std::vector<BagTopic>& topics() const = 0;
  /// The next message on one of `wanted` topics (names), decoded; nullopt at the end. A wanted
  /// topic whose type slam2d does not decode is an Error naming it.
  virtual std::optional<DecodedRecord> next(const std::vector<std::string>& wanted) = 0;
  /// Fraction read, in [0, 1], for the progress line.
  virtual double progress() const = 0;
  /// What the reader worked around ("PATH: warning: ..."): a ROS 1 bag without an index, a tail cut short.
  virtual std::vector<std::string> warnings() const { return {}; }
};

}  // namespace slam2d
