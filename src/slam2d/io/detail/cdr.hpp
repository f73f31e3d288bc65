// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CDR (OMG XCDR1, as ROS 2's rmw writes it) decoding of the few message types slam2d reads from
// ROS 2 bags (MCAP and rosbag2 sqlite3) into the plain structs of io/bag_source.hpp, and their
// encoding for the bag writers.
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
#include <string_view>
#include <type_traits>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/io/bag_source.hpp"

namespace slam2d::detail {

/// A malformed CDR message; what() is the bare reason, the caller adds the path and the message.
class CdrError : public Error {
 public:
  using Error::Error;
};

/// Writes XCDR1 little-endian (encapsulation 00 01 00 00), aligning each primitive to its size
/// from the end of the encapsulation header: the inverse of the decoder below.
class CdrWriter {
 public:
  CdrWriter() : bytes_{0, 1, 0, 0} {}

  template <typename T>
  CdrWriter& put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    align(sizeof(T));
    const auto* raw = reinterpret_cast<const std::uint8_t*>(&value);
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));  // native little-endian (checked in cdr.cpp)
    return *this;
  }
  CdrWriter& string(std::string_view text);  // uint32 length with the NUL, the bytes, the NUL
  CdrWriter& count(std::size_t n);           // a sequence's uint32 element count (Error above 2^32 - 1)
  CdrWriter& time(double stamp);             // builtin_interfaces/Time; Error outside int32 seconds
  CdrWriter& header(double stamp, std::string_view frame_id);  // std_msgs/Header
  CdrWriter& zeros(std::size_t doubles);     // float64 zeros: covariances, unused vector parts
  CdrWriter& pose(const SE2& pose);          // geometry_msgs/Pose or Transform: (x, y, 0), yaw quaternion
  CdrWriter& raw(const std::uint8_t* data, std::size_t size);  // bytes as they are (uint8[] after count)
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  void align(std::size_t n) { bytes_.resize(bytes_.size() + (n - (bytes_.size() - 4) % n) % n, 0); }
  std::vector<std::uint8_t> bytes_;
};

/// The ROS 2 message types slam2d decodes.
enum class Ros2Type { kLaserScan, kOdometry, kTFMessage, kImu };

/// The type named "sensor_msgs/msg/LaserScan" etc., or nullopt for a type slam2d does not decode.
std::optional<Ros2Type> ros2_type(const std::string& name);

/// Decodes one CDR message of `type` from data[0, size). `is_static_tf` sets
/// DecodedTransforms::is_static (the topic is /tf_static). Throws CdrError.
DecodedMessage decode_cdr(Ros2Type type, const std::uint8_t* data, std::size_t size, bool is_static_tf);

/// The ROS 2 type of a message ("sensor_msgs/msg/LaserScan", ...) and its CDR encoding: the exact
/// inverse of decode_cdr (angles and ranges of a scan rounded to float32, as the type stores them).
/// Throws Error for a value the type cannot hold (a stamp before 1901 or after 2038).
const char* ros2_type_name(const DecodedMessage& message);
std::vector<std::uint8_t> encode_cdr(const DecodedMessage& message);

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
