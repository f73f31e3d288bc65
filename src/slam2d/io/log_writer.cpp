// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/log_writer.hpp"

#include <algorithm>
#include <filesystem>
#include <memory>
#include <numeric>
#include <optional>

#include "slam2d/core/error.hpp"
#include "slam2d/io/bag_sink.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/io/mcap_writer.hpp"
#include "slam2d/io/ros1_bag_writer.hpp"
#include "slam2d/io/rosbag2_writer.hpp"

namespace slam2d {
namespace {

bool is_old_carmen_laser(const std::string& type) {
  return type == "FLASER" || type == "RLASER" || type == "ROBOTLASER1" || type.starts_with("RAWLASER");
}

LogWriteReport write_carmen(const std::string& path, const std::vector<SensorMessage>& messages,
                            const std::vector<std::string>& comments) {
  LogWriteReport report;
  std::vector<SensorMessage> carmen;
  carmen.reserve(messages.size());
  for (const SensorMessage& message : messages) {
    if (std::holds_alternative<ImuMessage>(message)) {
      ++report.not_written;
      continue;
    }
    carmen.push_back(message);
    if (auto* laser = std::get_if<LaserMessage>(&carmen.back())) {
      if (!is_old_carmen_laser(laser->type)) laser->type = laser->has_poses ? "ROBOTLASER1" : "RAWLASER1";
      ++report.scans;
    }
    report.odometry += std::holds_alternative<OdometryMessage>(message) ? 1 : 0;
    report.true_poses += std::holds_alternative<TruePoseMessage>(message) ? 1 : 0;
  }
  write_carmen_log(path, comments, carmen);
  return report;
}

std::unique_ptr<BagSink> open_sink(const std::string& path, LogFormat format) {
  switch (format) {
    case LogFormat::kRos1Bag: return open_ros1_bag_writer(path);
    case LogFormat::kMcap: return open_mcap_writer(path);
    case LogFormat::kRosbag2: return open_rosbag2_writer(path);
    case LogFormat::kCarmen: break;
  }
  throw Error(path + ": not a bag format");
}

/// The messages of a log as bag messages, in the order `order` gives.
class BagWriting {
 public:
  BagWriting(BagSink& sink, const BagLayout& layout, bool has_odometry_readings)
      : sink_(sink), layout_(layout), has_odometry_readings_(has_odometry_readings) {}

  void mounting(const LaserMessage& laser, double at) {
    const bool rear = laser.type == "RLASER";
    std::optional<SE2>& known = rear ? rear_mounting_ : front_mounting_;
    if (known && known->vector() == laser.scan.T_robot_sensor.vector()) return;
    known = laser.scan.T_robot_sensor;
    const std::string& frame = rear ? layout_.rear_laser_frame : layout_.laser_frame;
    sink_.write("/tf_static", at,
                DecodedTransforms{true, {{at, layout_.base_frame, frame, laser.scan.T_robot_sensor}}});
  }

  void operator()(const LaserMessage& laser) {
    const bool rear = laser.type == "RLASER";
    DecodedScan scan{rear ? layout_.rear_laser_frame : layout_.laser_frame, laser.scan};
    scan.scan.T_robot_sensor = SE2();
    sink_.write(rear ? layout_.rear_scan_topic : layout_.scan_topic, laser.scan.stamp, scan);
    ++report.scans;
    if (!has_odometry_readings_ && laser.has_poses) odometry({.stamp = laser.scan.stamp, .pose = laser.odom_pose});
  }
  void operator()(const OdometryMessage& message) { odometry(message.reading); }
  void operator()(const TruePoseMessage&) { ++report.true_poses, ++report.not_written; }
  void operator()(const ImuMessage& message) {
    sink_.write(layout_.imu_topic, message.reading.stamp, DecodedImu{layout_.base_frame, message.reading});
    ++report.imu;
  }

  LogWriteReport report;

 private:
  void odometry(const OdometryReading& reading) {
    sink_.write(layout_.odom_topic, reading.stamp, DecodedOdometry{layout_.odom_frame, layout_.base_frame, reading});
    sink_.write("/tf", reading.stamp,
                DecodedTransforms{false, {{reading.stamp, layout_.odom_frame, layout_.base_frame, reading.pose}}});
    ++report.odometry;
  }

  BagSink& sink_;
  const BagLayout& layout_;
  bool has_odometry_readings_;
  std::optional<SE2> front_mounting_;
  std::optional<SE2> rear_mounting_;
};

LogWriteReport write_bag(const std::string& path, LogFormat format, const std::vector<SensorMessage>& messages,
                         const BagLayout& layout) {
  std::vector<std::size_t> order(messages.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  if (format != LogFormat::kRos1Bag) {  // ROS 2 writes in receive-time order
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return stamp_of(messages[a]) < stamp_of(messages[b]); });
  }
  const bool has_odometry_readings = std::any_of(messages.begin(), messages.end(), [](const SensorMessage& m) {
    return std::holds_alternative<OdometryMessage>(m);
  });
  double first_stamp = 0.0;
  for (std::size_t i = 0; i < messages.size(); ++i) first_stamp = i == 0 ? stamp_of(messages[i]) : std::min(first_stamp, stamp_of(messages[i]));

  std::unique_ptr<BagSink> sink = open_sink(path, format);
  BagWriting writing(*sink, layout, has_odometry_readings);
  bool first_mounting = true;
  for (std::size_t i : order) {
    if (const auto* laser = std::get_if<LaserMessage>(&messages[i])) {
      writing.mounting(*laser, first_mounting ? first_stamp : laser->scan.stamp);  // the first before any message
      first_mounting = false;
    }
    std::visit(writing, messages[i]);
  }
  sink->commit();
  return writing.report;
}

}  // namespace

LogFormat log_format_for_output(const std::string& path) {
  const std::filesystem::path p(path);
  if (!path.empty() && path.back() == '/') return LogFormat::kRosbag2;
  const std::string extension = p.extension().string();
  if (extension == ".bag") return LogFormat::kRos1Bag;
  if (extension == ".mcap") return LogFormat::kMcap;
  if (extension.empty()) return LogFormat::kRosbag2;
  return LogFormat::kCarmen;
}

LogFormat parse_log_format(const std::string& name) {
  for (LogFormat format : {LogFormat::kCarmen, LogFormat::kRos1Bag, LogFormat::kMcap, LogFormat::kRosbag2}) {
    if (name == log_format_name(format)) return format;
  }
  throw Error("unknown log format '" + name + "' (carmen, ros1, mcap, rosbag2)");
}

LogWriteReport write_log(const std::string& path, LogFormat format, const std::vector<SensorMessage>& messages,
                         const std::vector<std::string>& comments, const BagLayout& layout) {
  if (format == LogFormat::kCarmen) return write_carmen(path, messages, comments);
  try {
    return write_bag(path, format, messages, layout);
  } catch (const Error& e) {
    const std::string what = e.what();
    throw Error(what.starts_with(path) ? what : path + ": " + what);
  }
}

}  // namespace slam2d
