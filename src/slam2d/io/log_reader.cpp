// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/log_reader.hpp"

#include <cmath>
#include <filesystem>

#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry_chain.hpp"
#include "slam2d/io/mcap.hpp"
#include "slam2d/io/ros1_bag.hpp"
#include "slam2d/io/rosbag2.hpp"

namespace slam2d {

LogFormat detect_log_format(const std::string& path) {
  if (is_rosbag2(path)) return LogFormat::kRosbag2;
  if (std::filesystem::is_regular_file(path)) {
    if (is_ros1_bag(path)) return LogFormat::kRos1Bag;
    if (is_mcap(path)) return LogFormat::kMcap;
  }
  return LogFormat::kCarmen;
}

const char* log_format_name(LogFormat format) {
  switch (format) {
    case LogFormat::kCarmen: return "carmen";
    case LogFormat::kRos1Bag: return "ros1";
    case LogFormat::kMcap: return "mcap";
    case LogFormat::kRosbag2: return "rosbag2";
  }
  return "?";
}

namespace {

std::unique_ptr<BagSource> open_bag(LogFormat format, const std::string& path) {
  switch (format) {
    case LogFormat::kRos1Bag: return open_ros1_bag(path);
    case LogFormat::kMcap: return open_mcap(path);
    case LogFormat::kRosbag2: return open_rosbag2(path);
    case LogFormat::kCarmen: break;
  }
  throw Error(path + ": not a bag");
}

}  // namespace

LogReader::LogReader(const std::string& path, LogReaderOptions options) : format_(detect_log_format(path)) {
  if (format_ == LogFormat::kCarmen) {
    carmen_ = std::make_unique<CarmenReader>(path, std::move(options.carmen));
  } else {
    bag_ = std::make_unique<BagLogReader>(open_bag(format_, path), std::move(options.bag), options.carmen.geometry);
  }
  check(std::isfinite(options.odometry_time_offset), path + ": the odometry time offset must be finite");
  if (options.odometry_time_offset != 0.0) {
    std::vector<SensorMessage> messages;
    while (auto message = next_from_file()) messages.push_back(std::move(*message));
    shift_scan_odometry(messages, -options.odometry_time_offset);
    shifted_ = std::move(messages);
  }
}

LogReader::~LogReader() = default;
LogReader::LogReader(LogReader&&) noexcept = default;
LogReader& LogReader::operator=(LogReader&&) noexcept = default;

std::optional<SensorMessage> LogReader::next_from_file() { return carmen_ ? carmen_->next() : bag_->next(); }

std::optional<SensorMessage> LogReader::next() {
  if (!shifted_) return next_from_file();
  if (served_ == shifted_->size()) return std::nullopt;
  return std::move((*shifted_)[served_++]);
}

double LogReader::progress() const {
  if (shifted_) return shifted_->empty() ? 1.0 : static_cast<double>(served_) / static_cast<double>(shifted_->size());
  return carmen_ ? carmen_->progress() : bag_->progress();
}
const std::string& LogReader::path() const { return carmen_ ? carmen_->path() : bag_->path(); }
CarmenStats LogReader::stats() const { return carmen_ ? carmen_->stats() : CarmenStats{}; }

std::vector<SensorMessage> read_all(LogReader& reader, const std::function<void(double, std::size_t)>& progress) {
  std::vector<SensorMessage> messages;
  while (auto message = reader.next()) {
    messages.push_back(std::move(*message));
    if (progress && messages.size() % 4096 == 0) progress(reader.progress(), messages.size());
  }
  return messages;
}

}  // namespace slam2d
