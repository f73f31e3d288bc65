// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The ROS 2 message definitions of the types slam2d writes, as MCAP "ros2msg" schemas: the type's
// fields, then each type it uses once, after a line of 80 '=' and "MSG: package/Type" (the form
// rosbag2 and Foxglove write and read). The fields and their order are those of the ROS 2
// interfaces (common_interfaces, rcl_interfaces); comments and constants other than PointField's
// datatypes are left out.

#include <string>
#include <string_view>

namespace slam2d::detail {

/// The schema of `type` ("sensor_msgs/msg/LaserScan"); Error for a type slam2d does not write.
std::string ros2msg_schema(std::string_view type);

}  // namespace slam2d::detail
