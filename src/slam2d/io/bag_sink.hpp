// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The contract of a bag writer (ROS 1 bag, MCAP as ROS 2 writes it, rosbag2 folder): the mirror of
// io/bag_source.hpp. A writer takes the plain Decoded* structs of the messages slam2d reads, on
// named topics, encodes them in its format's wire encoding (ROS 1 serialization or CDR) with the
// type's standard definition (so that rosbag, ros2 bag, Foxglove and slam2d's readers read them),
// and writes the file atomically: nothing appears at the path unless commit() succeeds.
//
// The message types and their topics' types:
//   DecodedScan        sensor_msgs/LaserScan   (scan.T_robot_sensor is not written: the mounting
//                                               is a static transform)
//   DecodedOdometry    nav_msgs/Odometry       (pose x, y, yaw; twist.linear.x = tv,
//                                               twist.angular.z = rv; covariances zero)
//   DecodedTransforms  tf2_msgs/TFMessage
//   DecodedImu         sensor_msgs/Imu         (orientation from the reading's roll, pitch and yaw 0;
//                                               angular_velocity.z = yaw_rate)
// A topic's type is fixed by its first message; a later message of another type on it is an Error.

#include <string>

#include "slam2d/io/bag_source.hpp"

namespace slam2d {

class BagSink {
 public:
  virtual ~BagSink() = default;
  /// Appends one message on `topic` received at `receive_time` (s; ROS 1 record time, MCAP
  /// log_time and publish_time, rosbag2 timestamp). Messages may come in any time order: ROS 1
  /// keeps the order given (recording order), ROS 2 formats are written in receive-time order.
  virtual void write(const std::string& topic, double receive_time, const DecodedMessage& message) = 0;
  /// Writes the index or summary, closes the file and renames it into place. Throws Error("PATH: ...").
  virtual void commit() = 0;
};

}  // namespace slam2d
