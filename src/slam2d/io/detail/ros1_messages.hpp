// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ROS 1 serialization (http://wiki.ros.org/msg, little-endian; strings and arrays carry a uint32
// length; time is uint32 sec + uint32 nsec) of the four message types slam2d reads and writes.

#include <optional>
#include <string_view>
#include <vector>

#include "slam2d/io/bag_source.hpp"
#include "slam2d/io/detail/ros1_records.hpp"
#include "slam2d/io/detail/ros1_wire.hpp"

namespace slam2d::ros1 {

enum class MessageType { kLaserScan, kOdometry, kTFMessage, kImu };

/// The type slam2d decodes under a ROS 1 type name ("sensor_msgs/LaserScan"), or nullopt.
std::optional<MessageType> message_type(std::string_view name);
/// The md5sum of the message definition slam2d decodes, as bags record it.
std::string_view md5sum(MessageType type);

/// The type of a message slam2d writes, and the ROS 1 name of a type.
MessageType message_type_of(const DecodedMessage& message);
std::string_view type_name(MessageType type);

/// A ROS 1 time from s; Error outside [0, 2^32) s or not finite.
Time to_time(double stamp);

/// One message serialized with header.seq `seq`: the exact inverse of decode_message (a scan's
/// angles, limits and ranges rounded to float32, as the type stores them). Throws Error for a stamp
/// ROS 1 time cannot hold.
std::vector<std::uint8_t> encode_message(const DecodedMessage& message, std::uint32_t seq);

/// One serialized message, decoded; every byte must be used. `is_static` marks a TFMessage read
/// from /tf_static. Throws Error for data too short or too long for the type.
DecodedMessage decode_message(MessageType type, Bytes data, bool is_static);


}  // namespace slam2d::ros1
