// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/detail/ros1_messages.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <variant>

#include "slam2d/io/detail/ros_quaternion.hpp"
#include "slam2d/io/detail/ros_time.hpp"
#include "slam2d/io/input_limits.hpp"

namespace slam2d::ros1 {

namespace {

struct TypeInfo {
  MessageType type;
  std::string_view name;
  std::string_view md5sum;
};
constexpr std::array<TypeInfo, 4> kTypes = {{
    {MessageType::kLaserScan, "sensor_msgs/LaserScan", "90c7ef2dc6895d81024acba2ac42f369"},
    {MessageType::kOdometry, "nav_msgs/Odometry", "cd5e73d190d741a2f92e81eda573aca7"},
    {MessageType::kTFMessage, "tf2_msgs/TFMessage", "94810edda583a504dfda3829e70d7eec"},
    {MessageType::kImu, "sensor_msgs/Imu", "6a62c6daae103f4ff57a132d6f95cec2"},
}};

// std_msgs/Header: uint32 seq, time stamp, string frame_id.
struct Header {
  double stamp = 0.0;
  std::string frame_id;
};
Header read_header(WireReader& reader) {
  reader.skip(4);  // seq
  const double sec = reader.u32();
  const double nsec = reader.u32();
  return {sec + nsec * 1e-9, reader.string()};
}

detail::RosQuaternion read_quaternion(WireReader& reader) {
  detail::RosQuaternion q;
  q.x = reader.f64();
  q.y = reader.f64();
  q.z = reader.f64();
  q.w = reader.f64();
  return q;
}

constexpr std::size_t kVector3Bytes = 3 * 8;
constexpr std::size_t kCovariance3Bytes = 9 * 8;   // float64[9]
constexpr std::size_t kCovariance6Bytes = 36 * 8;  // float64[36]

std::vector<double> read_float32_array(WireReader& reader) {
  const std::size_t n = reader.count(4);
  std::vector<double> values(n);
  for (double& value : values) value = reader.f32();
  return values;
}

// sensor_msgs/LaserScan.
DecodedScan read_laser_scan(WireReader& reader) {
  DecodedScan out;
  Header header = read_header(reader);
  out.frame_id = std::move(header.frame_id);
  LaserScan& scan = out.scan;
  scan.stamp = header.stamp;
  scan.angle_min = reader.f32();
  reader.skip(4);  // angle_max: angle_min + (n - 1) angle_increment
  scan.angle_increment = reader.f32();
  reader.skip(8);  // time_increment, scan_time
  scan.range_min = reader.f32();
  scan.range_max = reader.f32();
  scan.ranges = read_float32_array(reader);
  check_beam_count(scan.ranges.size());
  scan.intensities = read_float32_array(reader);
  return out;
}

// nav_msgs/Odometry: header, child_frame_id, PoseWithCovariance, TwistWithCovariance.
DecodedOdometry read_odometry(WireReader& reader) {
  DecodedOdometry out;
  Header header = read_header(reader);
  out.frame_id = std::move(header.frame_id);
  out.child_frame_id = reader.string();
  OdometryReading& reading = out.reading;
  reading.stamp = header.stamp;
  const double x = reader.f64();
  const double y = reader.f64();
  reader.skip(8);  // z
  const detail::RosQuaternion q = read_quaternion(reader);
  reader.skip(kCovariance6Bytes);
  reading.pose = SE2(x, y, q.yaw());
  reading.tv = reader.f64();  // twist.linear.x
  reader.skip(2 * 8 + 2 * 8);  // linear y z, angular x y
  reading.rv = reader.f64();   // twist.angular.z
  reader.skip(kCovariance6Bytes);
  return out;
}

// tf2_msgs/TFMessage: geometry_msgs/TransformStamped[].
DecodedTransforms read_transforms(WireReader& reader, bool is_static) {
  // The smallest TransformStamped: seq, stamp, two empty strings, translation, rotation.
  constexpr std::size_t kMinTransformBytes = 4 + 8 + 4 + 4 + kVector3Bytes + 4 * 8;
  DecodedTransforms out;
  out.is_static = is_static;
  const std::size_t n = reader.count(kMinTransformBytes);
  out.transforms.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    DecodedTransform& transform = out.transforms.emplace_back();
    Header header = read_header(reader);
    transform.stamp = header.stamp;
    transform.parent = std::move(header.frame_id);
    transform.child = reader.string();
    const double x = reader.f64();
    const double y = reader.f64();
    reader.skip(8);  // z
    const detail::RosQuaternion q = read_quaternion(reader);
    transform.T_parent_child = SE2(x, y, q.yaw());
  }
  return out;
}

// sensor_msgs/Imu: header, orientation + covariance, angular_velocity + covariance,
// linear_acceleration + covariance.
DecodedImu read_imu(WireReader& reader) {
  DecodedImu out;
  Header header = read_header(reader);
  out.reading.stamp = header.stamp;
  out.frame_id = std::move(header.frame_id);
  const detail::RosQuaternion q = read_quaternion(reader);
  out.reading.roll = q.roll();
  out.reading.pitch = q.pitch();
  reader.skip(kCovariance3Bytes);
  reader.skip(2 * 8);  // angular_velocity x y
  out.reading.yaw_rate = reader.f64();
  reader.skip(kCovariance3Bytes);
  reader.skip(kVector3Bytes + kCovariance3Bytes);  // linear_acceleration
  return out;
}

void write_header(WireWriter& out, std::uint32_t seq, double stamp, std::string_view frame_id) {
  const Time time = to_time(stamp);
  out.u32(seq).u32(time.sec).u32(time.nsec).string(frame_id);
}

void write_pose(WireWriter& out, const SE2& pose) {  // geometry_msgs/Pose or Transform, planar
  const detail::RosQuaternion q = detail::RosQuaternion::from_yaw(pose.theta());
  out.f64(pose.x()).f64(pose.y()).f64(0.0).f64(q.x).f64(q.y).f64(q.z).f64(q.w);
}

void write_zeros(WireWriter& out, std::size_t doubles) {
  for (std::size_t i = 0; i < doubles; ++i) out.f64(0.0);
}

void write_float32_array(WireWriter& out, const std::vector<double>& values) {
  out.u32(static_cast<std::uint32_t>(values.size()));
  for (double value : values) out.f32(static_cast<float>(value));
}

struct Encode {
  WireWriter& out;
  std::uint32_t seq;
  void operator()(const DecodedScan& m) const {
    const LaserScan& scan = m.scan;
    write_header(out, seq, scan.stamp, m.frame_id);
    out.f32(static_cast<float>(scan.angle_min)).f32(static_cast<float>(scan.angle_max()));
    out.f32(static_cast<float>(scan.angle_increment)).f32(0.0f).f32(0.0f);  // time_increment, scan_time
    out.f32(static_cast<float>(scan.range_min)).f32(static_cast<float>(scan.range_max));
    write_float32_array(out, scan.ranges);
    write_float32_array(out, scan.intensities);
  }
  void operator()(const DecodedOdometry& m) const {
    write_header(out, seq, m.reading.stamp, m.frame_id);
    out.string(m.child_frame_id);
    write_pose(out, m.reading.pose);
    write_zeros(out, 36);                                        // pose covariance
    out.f64(m.reading.tv);                                       // twist.linear.x
    write_zeros(out, 4);                                         // linear y z, angular x y
    out.f64(m.reading.rv);                                       // twist.angular.z
    write_zeros(out, 36);                                        // twist covariance
  }
  void operator()(const DecodedTransforms& m) const {
    out.u32(static_cast<std::uint32_t>(m.transforms.size()));
    for (const DecodedTransform& transform : m.transforms) {
      write_header(out, 0, transform.stamp, transform.parent);
      out.string(transform.child);
      write_pose(out, transform.T_parent_child);
    }
  }
  void operator()(const DecodedImu& m) const {
    write_header(out, seq, m.reading.stamp, m.frame_id);
    const detail::RosQuaternion q = detail::RosQuaternion::from_euler(m.reading.roll, m.reading.pitch, 0.0);
    out.f64(q.x).f64(q.y).f64(q.z).f64(q.w);
    write_zeros(out, 9 + 2);  // orientation covariance, angular_velocity x y
    out.f64(m.reading.yaw_rate);
    write_zeros(out, 9 + 3 + 9);  // its covariance, linear_acceleration and its covariance
  }
};

}  // namespace

MessageType message_type_of(const DecodedMessage& message) {
  struct Type {
    MessageType operator()(const DecodedScan&) const { return MessageType::kLaserScan; }
    MessageType operator()(const DecodedOdometry&) const { return MessageType::kOdometry; }
    MessageType operator()(const DecodedTransforms&) const { return MessageType::kTFMessage; }
    MessageType operator()(const DecodedImu&) const { return MessageType::kImu; }
  };
  return std::visit(Type{}, message);
}

std::string_view type_name(MessageType type) { return kTypes[static_cast<std::size_t>(type)].name; }

Time to_time(double stamp) {
  const detail::SplitStamp t = detail::split_stamp(stamp, 0.0, 4294967295.0, "a ROS 1 time (0 to 2^32 s)");
  return {static_cast<std::uint32_t>(t.sec), t.nsec};
}

std::vector<std::uint8_t> encode_message(const DecodedMessage& message, std::uint32_t seq) {
  WireWriter out;
  std::visit(Encode{out, seq}, message);
  return out.take();
}

std::optional<MessageType> message_type(std::string_view name) {
  for (const TypeInfo& info : kTypes) {
    if (info.name == name) return info.type;
  }
  return std::nullopt;
}

std::string_view md5sum(MessageType type) { return kTypes[static_cast<std::size_t>(type)].md5sum; }


DecodedMessage decode_message(MessageType type, Bytes data, bool is_static) {
  WireReader reader(data);
  DecodedMessage message = [&]() -> DecodedMessage {
    switch (type) {
      case MessageType::kLaserScan: return read_laser_scan(reader);
      case MessageType::kOdometry: return read_odometry(reader);
      case MessageType::kTFMessage: return read_transforms(reader, is_static);
      case MessageType::kImu: return read_imu(reader);
    }
    throw Error("unknown message type");
  }();
  if (reader.remaining() != 0) {
    throw Error(std::to_string(reader.remaining()) + " bytes left over after a " +
                std::string(kTypes[static_cast<std::size_t>(type)].name) + " of " + std::to_string(data.size()) +
                " bytes");
  }
  return message;
}

}  // namespace slam2d::ros1
