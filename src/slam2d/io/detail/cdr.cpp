// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/detail/cdr.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>
#include <utility>
#include <variant>

#include "slam2d/io/detail/ros_quaternion.hpp"
#include "slam2d/io/detail/ros_time.hpp"
#include "slam2d/io/input_limits.hpp"

namespace slam2d::detail {
namespace {

constexpr std::size_t kEncapsulationSize = 4;

/// Reads XCDR1 primitives, strings and sequences with alignment and bounds checks.
class CdrReader {
 public:
  CdrReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
    if (size < kEncapsulationSize) throw CdrError("message of " + std::to_string(size) + " bytes has no CDR header");
    // Encapsulation identifier: 0x0000 CDR_BE, 0x0001 CDR_LE (XCDR1 plain CDR).
    if (data[0] != 0 || data[1] > 1) {
      throw CdrError("unsupported CDR encapsulation " + std::to_string(data[0]) + " " + std::to_string(data[1]) +
                     " (only plain CDR, 00 00 or 00 01)");
    }
    little_endian_ = data[1] == 1;
    pos_ = kEncapsulationSize;
  }

  template <typename T>
  T read() {
    static_assert(std::is_arithmetic_v<T>);
    align(sizeof(T));
    need(sizeof(T), "a field");
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    if (little_endian_ != (std::endian::native == std::endian::little)) std::reverse(bytes, bytes + sizeof(T));
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }

  std::string string() {
    const std::uint32_t length = read<std::uint32_t>();  // including the NUL
    need(length, "a string of " + std::to_string(length) + " bytes");
    std::size_t used = length;
    while (used > 0 && data_[pos_ + used - 1] == 0) --used;  // the NUL (lenient: 0 length, extra NULs)
    std::string text(reinterpret_cast<const char*>(data_ + pos_), used);
    pos_ += length;
    return text;
  }

  /// A sequence's count, checked (before anything is allocated) against the bytes left for
  /// elements of at least `element_size` bytes each.
  std::size_t sequence(std::size_t element_size, const char* what) {
    const std::uint32_t count = read<std::uint32_t>();
    need(static_cast<std::size_t>(count) * element_size, std::string("a sequence of ") + std::to_string(count) + " " + what);
    return count;
  }

  double time() {
    const auto sec = read<std::int32_t>();
    const auto nanosec = read<std::uint32_t>();
    return static_cast<double>(sec) + static_cast<double>(nanosec) * 1e-9;
  }

  void skip_doubles(std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) read<double>();
  }

 private:
  void align(std::size_t n) {
    const std::size_t offset = pos_ - kEncapsulationSize;
    const std::size_t padding = (n - offset % n) % n;
    need(padding, "alignment padding");
    pos_ += padding;
  }
  void need(std::size_t bytes, const std::string& what) const {
    if (bytes > size_ - pos_) {
      throw CdrError("truncated CDR message: " + what + " at byte " + std::to_string(pos_) + " runs past its end (" +
                     std::to_string(size_) + " bytes)");
    }
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  bool little_endian_ = true;
};

struct Header {
  double stamp = 0.0;
  std::string frame_id;
};

Header read_header(CdrReader& in) {
  Header header;
  header.stamp = in.time();
  header.frame_id = in.string();
  return header;
}

RosQuaternion read_quaternion(CdrReader& in) {
  RosQuaternion q{};
  q.x = in.read<double>();
  q.y = in.read<double>();
  q.z = in.read<double>();
  q.w = in.read<double>();
  return q;
}

/// geometry_msgs/Pose or Transform (a Point or Vector3, then a Quaternion), made planar.
SE2 read_planar_pose(CdrReader& in) {
  const double x = in.read<double>();
  const double y = in.read<double>();
  in.read<double>();  // z
  const RosQuaternion q = read_quaternion(in);
  return SE2(x, y, q.yaw());
}

DecodedScan read_laser_scan(CdrReader& in) {
  DecodedScan out;
  Header header = read_header(in);
  out.frame_id = std::move(header.frame_id);
  LaserScan& scan = out.scan;
  scan.stamp = header.stamp;
  scan.angle_min = in.read<float>();
  in.read<float>();  // angle_max: implied by angle_min, angle_increment and the beam count
  scan.angle_increment = in.read<float>();
  in.read<float>();  // time_increment
  in.read<float>();  // scan_time
  scan.range_min = in.read<float>();
  scan.range_max = in.read<float>();
  scan.ranges.resize(in.sequence(sizeof(float), "ranges"));
  check_beam_count(scan.ranges.size());
  for (double& range : scan.ranges) range = in.read<float>();
  scan.intensities.resize(in.sequence(sizeof(float), "intensities"));
  for (double& intensity : scan.intensities) intensity = in.read<float>();
  return out;
}

DecodedOdometry read_odometry(CdrReader& in) {
  DecodedOdometry out;
  Header header = read_header(in);
  out.frame_id = std::move(header.frame_id);
  out.child_frame_id = in.string();
  out.reading.stamp = header.stamp;
  out.reading.pose = read_planar_pose(in);
  in.skip_doubles(36);  // pose covariance
  out.reading.tv = in.read<double>();  // twist.linear.x
  in.skip_doubles(2);                  // linear.y, linear.z
  in.skip_doubles(2);                  // angular.x, angular.y
  out.reading.rv = in.read<double>();  // twist.angular.z
  in.skip_doubles(36);                 // twist covariance
  return out;
}

DecodedTransforms read_tf_message(CdrReader& in, bool is_static) {
  DecodedTransforms out;
  out.is_static = is_static;
  // The smallest TransformStamped: time 8, two empty strings 4 + 4, 7 doubles 56.
  const std::size_t count = in.sequence(72, "transforms");
  out.transforms.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    DecodedTransform transform;
    Header header = read_header(in);
    transform.stamp = header.stamp;
    transform.parent = std::move(header.frame_id);
    transform.child = in.string();
    transform.T_parent_child = read_planar_pose(in);
    out.transforms.push_back(std::move(transform));
  }
  return out;
}

DecodedImu read_imu(CdrReader& in) {
  DecodedImu out;
  Header header = read_header(in);
  out.reading.stamp = header.stamp;
  out.frame_id = std::move(header.frame_id);
  const RosQuaternion q = read_quaternion(in);
  out.reading.roll = q.roll();
  out.reading.pitch = q.pitch();
  in.skip_doubles(9);  // orientation covariance
  in.skip_doubles(2);  // angular_velocity x, y
  out.reading.yaw_rate = in.read<double>();
  in.skip_doubles(9);      // angular velocity covariance
  in.skip_doubles(3 + 9);  // linear acceleration and its covariance
  return out;
}

static_assert(std::endian::native == std::endian::little, "CdrWriter writes native little-endian primitives");

void write_laser_scan(CdrWriter& out, const DecodedScan& message) {
  const LaserScan& scan = message.scan;
  out.header(scan.stamp, message.frame_id);
  out.put(static_cast<float>(scan.angle_min)).put(static_cast<float>(scan.angle_max()));
  out.put(static_cast<float>(scan.angle_increment)).put(0.0f).put(0.0f);  // time_increment, scan_time
  out.put(static_cast<float>(scan.range_min)).put(static_cast<float>(scan.range_max));
  out.count(scan.ranges.size());
  for (double range : scan.ranges) out.put(static_cast<float>(range));
  out.count(scan.intensities.size());
  for (double intensity : scan.intensities) out.put(static_cast<float>(intensity));
}

void write_odometry(CdrWriter& out, const DecodedOdometry& message) {
  out.header(message.reading.stamp, message.frame_id).string(message.child_frame_id);
  out.pose(message.reading.pose).zeros(36);              // pose, covariance
  out.put(message.reading.tv).zeros(2).zeros(2).put(message.reading.rv);  // twist: linear, angular
  out.zeros(36);                                         // twist covariance
}

void write_tf_message(CdrWriter& out, const DecodedTransforms& message) {
  out.count(message.transforms.size());
  for (const DecodedTransform& transform : message.transforms) {
    out.header(transform.stamp, transform.parent).string(transform.child).pose(transform.T_parent_child);
  }
}

void write_imu(CdrWriter& out, const DecodedImu& message) {
  out.header(message.reading.stamp, message.frame_id);
  const RosQuaternion q = RosQuaternion::from_euler(message.reading.roll, message.reading.pitch, 0.0);
  out.put(q.x).put(q.y).put(q.z).put(q.w).zeros(9);  // orientation, covariance
  out.zeros(2).put(message.reading.yaw_rate).zeros(9);       // angular velocity, covariance
  out.zeros(3 + 9);                                  // linear acceleration, covariance
}

}  // namespace

CdrWriter& CdrWriter::string(std::string_view text) {
  count(text.size() + 1);
  bytes_.insert(bytes_.end(), text.begin(), text.end());
  bytes_.push_back(0);
  return *this;
}

CdrWriter& CdrWriter::count(std::size_t n) {
  if (n > std::numeric_limits<std::uint32_t>::max()) throw Error("CDR: a sequence of " + std::to_string(n) + " elements");
  return put(static_cast<std::uint32_t>(n));
}

CdrWriter& CdrWriter::time(double stamp) {
  const SplitStamp t = split_stamp(stamp, std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max(),
                                   "builtin_interfaces/Time");
  return put(static_cast<std::int32_t>(t.sec)).put(t.nsec);
}

CdrWriter& CdrWriter::header(double stamp, std::string_view frame_id) { return time(stamp).string(frame_id); }

CdrWriter& CdrWriter::zeros(std::size_t doubles) {
  for (std::size_t i = 0; i < doubles; ++i) put(0.0);
  return *this;
}

CdrWriter& CdrWriter::pose(const SE2& pose) {
  const RosQuaternion q = RosQuaternion::from_yaw(pose.theta());
  return put(pose.x()).put(pose.y()).put(0.0).put(q.x).put(q.y).put(q.z).put(q.w);
}

CdrWriter& CdrWriter::raw(const std::uint8_t* data, std::size_t size) {
  bytes_.insert(bytes_.end(), data, data + size);
  return *this;
}

const char* ros2_type_name(const DecodedMessage& message) {
  struct Name {
    const char* operator()(const DecodedScan&) const { return "sensor_msgs/msg/LaserScan"; }
    const char* operator()(const DecodedOdometry&) const { return "nav_msgs/msg/Odometry"; }
    const char* operator()(const DecodedTransforms&) const { return "tf2_msgs/msg/TFMessage"; }
    const char* operator()(const DecodedImu&) const { return "sensor_msgs/msg/Imu"; }
  };
  return std::visit(Name{}, message);
}

std::vector<std::uint8_t> encode_cdr(const DecodedMessage& message) {
  CdrWriter out;
  struct Encode {
    CdrWriter& out;
    void operator()(const DecodedScan& m) const { write_laser_scan(out, m); }
    void operator()(const DecodedOdometry& m) const { write_odometry(out, m); }
    void operator()(const DecodedTransforms& m) const { write_tf_message(out, m); }
    void operator()(const DecodedImu& m) const { write_imu(out, m); }
  };
  std::visit(Encode{out}, message);
  return out.take();
}

std::optional<Ros2Type> ros2_type(const std::string& name) {
  if (name == "sensor_msgs/msg/LaserScan") return Ros2Type::kLaserScan;
  if (name == "nav_msgs/msg/Odometry") return Ros2Type::kOdometry;
  if (name == "tf2_msgs/msg/TFMessage") return Ros2Type::kTFMessage;
  if (name == "sensor_msgs/msg/Imu") return Ros2Type::kImu;
  return std::nullopt;
}

DecodedMessage decode_cdr(Ros2Type type, const std::uint8_t* data, std::size_t size, bool is_static_tf) {
  CdrReader in(data, size);
  switch (type) {
    case Ros2Type::kLaserScan: return read_laser_scan(in);
    case Ros2Type::kOdometry: return read_odometry(in);
    case Ros2Type::kTFMessage: return read_tf_message(in, is_static_tf);
    case Ros2Type::kImu: return read_imu(in);
  }
  throw CdrError("unknown message type");
}

Ros2Type wanted_type(const std::string& path, const std::string& topic, const std::string& type,
                     const std::string& encoding) {
  const std::optional<Ros2Type> known = ros2_type(type);
  if (!known) {
    throw Error(path + ": topic " + topic + " has type '" + type +
                "', which slam2d does not decode (sensor_msgs/msg/LaserScan, nav_msgs/msg/Odometry, "
                "tf2_msgs/msg/TFMessage, sensor_msgs/msg/Imu)");
  }
  if (encoding != "cdr") {
    throw Error(path + ": topic " + topic + " has message encoding '" + encoding + "'; slam2d reads 'cdr'");
  }
  return *known;
}

DecodedRecord decode_record(const std::string& path, const std::string& topic, Ros2Type type,
                            std::uint64_t receive_time_ns, std::size_t index, const std::uint8_t* data,
                            std::size_t size) {
  try {
    return DecodedRecord{topic, nanoseconds_to_seconds(receive_time_ns), index,
                         decode_cdr(type, data, size, topic == "/tf_static")};
  } catch (const CdrError& e) {
    throw Error(path + ": message " + std::to_string(index) + " on " + topic + ": " + e.what());
  }
}


double nanoseconds_to_seconds(std::uint64_t ns) {
  return static_cast<double>(ns / 1000000000u) + static_cast<double>(ns % 1000000000u) * 1e-9;
}

}  // namespace slam2d::detail
