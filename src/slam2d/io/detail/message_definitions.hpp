// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The message definitions of the types slam2d writes: the type's fields, then each type it uses
// once, after a line of 80 '=' and "MSG: package/Type", the form ROS 1 bags store in their
// connection records (`gendeps --cat`) and MCAP files in their "ros2msg" schemas (rosbag2,
// Foxglove). The fields and their order are those of the ROS interfaces (common_msgs /
// common_interfaces); comments and constants other than PointField's datatypes are left out. The
// two ROS versions differ only in std_msgs/Header (ROS 1: seq, time stamp, frame_id).

#include <string>
#include <string_view>

namespace slam2d::detail {

enum class RosVersion { kRos1, kRos2 };

/// The definition of `type` ("sensor_msgs/LaserScan" or ROS 2's "sensor_msgs/msg/LaserScan");
/// Error for a type slam2d does not write.
std::string message_definition(std::string_view type, RosVersion version);

}  // namespace slam2d::detail
