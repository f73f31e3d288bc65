// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CDR (OMG XCDR1, as ROS 2's rmw writes it) decoding of the few message types slam2d reads from
// ROS 2 bags (MCAP and rosbag2 sqlite3) into the plain structs of io/bag_source.hpp.
//
// A message is a 4-byte encapsulation header (00 01: little-endian, 00 00: big-endian; the last
// two bytes are options) followed by the fields in order. A primitive of size n is aligned to n
// bytes counted from the end of the encapsulation header; builtin_interfaces/Time is int32 sec +
// uint32 nanosec; a string is a uint32 length (including the terminating NUL) and its bytes; a
// sequence is a uint32 count and its elements; fixed arrays (covariances) have no count.
// Every length is checked against the bytes left: a malformed message is a CdrError, never an
// out-of-bounds read.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/io/bag_source.hpp"

namespace slam2d::detail {

/// A malformed CDR message; what() is the bare reason, the caller adds the path and the message.
class CdrError : public Error {
 public:
  using Error::Error;
};

/// The ROS 2 message types slam2d decodes.
enum class Ros2Type { kLaserScan, kOdometry, kTFMessage, kImu };

/// The type named "sensor_msgs/msg/LaserScan" etc., or nullopt for a type slam2d does not decode.
std::optional<Ros2Type> ros2_type(const std::string& name);

/// Decodes one CDR message of `type` from data[0, size). `is_static_tf` sets
/// DecodedTransforms::is_static (the topic is /tf_static). Throws CdrError.
DecodedMessage decode_cdr(Ros2Type type, const std::uint8_t* data, std::size_t size, bool is_static_tf);

/// The type of a topic the caller wants decoded; Error("PATH: topic TOPIC has type TYPE, which
/// slam2d does not decode ...") for another type or an encoding other than "cdr".
Ros2Type wanted_type(const std::string& path, const std::string& topic, const std::string& type,
                     const std::string& encoding);

/// One message of a ROS 2 bag decoded into a record; a malformed message is
/// Error("PATH: message INDEX on TOPIC: reason").
DecodedRecord decode_record(const std::string& path, const std::string& topic, Ros2Type type,
                            std::uint64_t receive_time_ns, std::size_t index, const std::uint8_t* data,
                            std::size_t size);


/// s from a ROS time in ns (exact to the ns for the integer second part).
double nanoseconds_to_seconds(std::uint64_t ns);

}  // namespace slam2d::detail
