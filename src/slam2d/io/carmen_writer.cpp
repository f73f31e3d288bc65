// SPDX-License-Identifier: BSD-3-Clause
// Writer for CARMEN 0.7 logger files (the formats read by carmen_reader.cpp).
//
// Every message ends in "ipc_timestamp slam2d logger_timestamp" with logger_timestamp equal to
// the ipc timestamp. Numbers are written with std::to_chars in their shortest exact form, so
// reading a written file gives back the same doubles.
//
// What the formats cannot hold is not written: FLASER/RLASER carry neither angles, maximum range
// nor the sensor mounting (write the PARAM lines for a non-default geometry with write_param) nor
// intensities; ROBOTLASER1/RAWLASER get laser_type 0, accuracy 0, remission_mode 0 (no
// intensities) or 1 (intensities), and ROBOTLASER1 zero velocities, safety distances and turn axis.
// Non-finite numbers, negative ranges and FLASER/RLASER/ROBOTLASER1 messages without poses are
// refused (Error): every written file reads back, and no pose is made up.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string_view>
#include <type_traits>
#include <variant>

#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/carmen.hpp"

namespace slam2d {

namespace {

constexpr std::string_view kHostname = "slam2d";

bool is_single_token(std::string_view text) {
  if (text.empty()) return false;
  for (char c : text) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f') return false;
  }
  return true;
}

}  // namespace

struct CarmenWriter::Impl {
  explicit Impl(const std::string& path) : file(path, has_gzip_extension(path)) {}

  [[noreturn]] void fail(const std::string& message) const { throw Error(file.path() + ": " + message); }

  void number(double value, std::string_view name) {
    if (!std::isfinite(value)) fail("cannot write a non-finite " + std::string(name));
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
    line += ' ';
    line.append(buffer, result.ptr);
  }

  void count(std::size_t value) {
    line += ' ';
    line += std::to_string(value);
  }

  void pose(const SE2& pose, std::string_view name) {
    number(pose.x(), name);
    number(pose.y(), name);
    number(pose.theta(), name);
  }

  void ranges(const std::vector<double>& values) {
    count(values.size());
    for (double r : values) {
      if (r < 0.0) fail("cannot write a negative range");
      number(r, "range");
    }
  }

  /// "ipc_timestamp hostname logger_timestamp", then the line goes to the file.
  void finish(double stamp) {
    number(stamp, "timestamp");
    line += ' ';
    line += kHostname;
    number(stamp, "timestamp");
    line += '\n';
    file.stream().write(line.data(), static_cast<std::streamsize>(line.size()));
    line.clear();
  }

  void start(std::string_view type) {
    if (committed) fail("write after commit");
    line.clear();
    line.append(type);
  }

  void old_laser(const LaserMessage& message);
  void new_laser(const LaserMessage& message, bool robot_laser);

  AtomicFile file;
  std::string line;
  bool committed = false;
};

// FLASER|RLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp
void CarmenWriter::Impl::old_laser(const LaserMessage& message) {
  start(message.type);
  ranges(message.scan.ranges);
  pose(message.laser_pose, "laser pose");
  pose(message.odom_pose, "odometry pose");
  finish(message.scan.stamp);
}

// ROBOTLASER1|RAWLASERk laser_type start_angle fov resolution max_range accuracy remission_mode
//   n ranges m remissions [laser pose, robot pose, tv rv forward_safety side_safety turn_axis] stamps
void CarmenWriter::Impl::new_laser(const LaserMessage& message, bool robot_laser) {
  const LaserScan& scan = message.scan;
  if (!scan.intensities.empty() && scan.intensities.size() != scan.ranges.size()) {
    fail("a scan has " + std::to_string(scan.intensities.size()) + " intensities for " +
         std::to_string(scan.ranges.size()) + " ranges");
  }
  start(message.type);
  count(0);  // laser_type
  number(scan.angle_min, "start_angle");
  number(message.field_of_view, "field_of_view");
  number(scan.angle_increment, "angular_resolution");
  number(scan.range_max, "maximum_range");
  count(0);                                   // accuracy
  count(scan.intensities.empty() ? 0 : 1);    // remission_mode
  ranges(scan.ranges);
  count(scan.intensities.size());
  for (double value : scan.intensities) number(value, "intensity");
  if (robot_laser) {
    pose(message.laser_pose, "laser pose");
    pose(message.odom_pose, "robot pose");
    for (int k = 0; k < 5; ++k) count(0);  // tv rv forward_safety_dist side_safety_dist turn_axis
  }
  finish(scan.stamp);
}

CarmenWriter::CarmenWriter(const std::string& path) : impl_(std::make_unique<Impl>(path)) {}
CarmenWriter::~CarmenWriter() = default;
CarmenWriter::CarmenWriter(CarmenWriter&&) noexcept = default;
CarmenWriter& CarmenWriter::operator=(CarmenWriter&&) noexcept = default;

void CarmenWriter::write_comment(const std::string& text) {
  if (!impl_) throw Error("CarmenWriter: used after move");
  std::string_view rest = text;
  do {  // one "# " line per line of text
    const std::size_t end = std::min(rest.find('\n'), rest.size());
    impl_->start("#");
    if (end > 0) impl_->line.append(" ").append(rest.substr(0, end));
    impl_->line += '\n';
    impl_->file.stream().write(impl_->line.data(), static_cast<std::streamsize>(impl_->line.size()));
    impl_->line.clear();
    rest.remove_prefix(std::min(end + 1, rest.size()));
  } while (!rest.empty());
}

void CarmenWriter::write_param(const std::string& name, const std::string& value, double stamp) {
  if (!impl_) throw Error("CarmenWriter: used after move");
  if (!is_single_token(name)) impl_->fail("PARAM name must be one non-empty word, got '" + name + "'");
  if (name.front() == '#') impl_->fail("PARAM name must not start with '#'");
  if (!is_single_token(value)) impl_->fail("PARAM " + name + ": value must be one non-empty word, got '" + value + "'");
  impl_->start("PARAM");
  impl_->line.append(" ").append(name).append(" ").append(value);
  impl_->finish(stamp);
}

void CarmenWriter::write(const LaserMessage& message) {
  if (!impl_) throw Error("CarmenWriter: used after move");
  const std::string_view type = message.type;
  if (!message.has_poses && (type == "FLASER" || type == "RLASER" || type == "ROBOTLASER1")) {
    impl_->fail(message.type + " needs the laser and odometry poses, but the message has none");
  }
  if (type == "FLASER" || type == "RLASER") {
    impl_->old_laser(message);
  } else if (type == "ROBOTLASER1") {
    impl_->new_laser(message, true);
  } else if (type.size() == 9 && type.starts_with("RAWLASER") && type[8] >= '1' && type[8] <= '4') {
    impl_->new_laser(message, false);
  } else {
    impl_->fail("unknown laser message type '" + message.type + "'");
  }
}

// ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp (accel is written as 0)
void CarmenWriter::write(const OdometryMessage& message) {
  if (!impl_) throw Error("CarmenWriter: used after move");
  impl_->start("ODOM");
  impl_->pose(message.reading.pose, "odometry pose");
  impl_->number(message.reading.tv, "tv");
  impl_->number(message.reading.rv, "rv");
  impl_->count(0);
  impl_->finish(message.reading.stamp);
}

// TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp
void CarmenWriter::write(const TruePoseMessage& message) {
  if (!impl_) throw Error("CarmenWriter: used after move");
  impl_->start("TRUEPOS");
  impl_->pose(message.true_pose, "true pose");
  impl_->pose(message.odom_pose, "odometry pose");
  impl_->finish(message.stamp);
}

bool CarmenWriter::write(const SensorMessage& message) {
  if (std::holds_alternative<ImuMessage>(message)) return false;
  std::visit([this](const auto& m) {
    if constexpr (!std::is_same_v<std::decay_t<decltype(m)>, ImuMessage>) write(m);
  }, message);
  return true;
}

void CarmenWriter::commit() {
  if (!impl_) throw Error("CarmenWriter: used after move");
  if (impl_->committed) impl_->fail("commit called twice");
  impl_->file.commit();
  impl_->committed = true;
}

}  // namespace slam2d
