// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A log of any format as the format-neutral sensor log (core/sensor_log.hpp): a CARMEN log (plain
// or .gz), a ROS 1 bag, an MCAP file or a rosbag2 folder (metadata.yaml beside its .mcap or .db3
// storage), told apart by content (the bag magics, metadata.yaml), not by name. What every command
// that reads a log uses.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "slam2d/core/sensor_log.hpp"
#include "slam2d/io/bag_log.hpp"
#include "slam2d/io/carmen.hpp"

namespace slam2d {

enum class LogFormat { kCarmen, kRos1Bag, kMcap, kRosbag2 };

/// The format of the log at `path` (a file or, for rosbag2, a folder or its metadata.yaml):
/// a bag by its magic, anything else is read as CARMEN (which refuses what it cannot parse).
LogFormat detect_log_format(const std::string& path);
const char* log_format_name(LogFormat format);  // "carmen", "ros1", "mcap", "rosbag2"

struct LogReaderOptions {
  CarmenReaderOptions carmen;  // its geometry overrides apply to every format; the rest is CARMEN's
  BagSelection bag;            // bags only: topics and frames
  // s: how far the odometry runs ahead of the laser (registration/odometry_time_offset.hpp); each
  // scan's odometry pose becomes the laser chain's at its stamp minus this (core/odometry_chain.hpp:
  // shift_scan_odometry). Nonzero: the log is read whole when opened. 0: as logged.
  double odometry_time_offset = 0.0;
};

class LogReader {
 public:
  /// Opens the log. Throws Error("PATH: ...") when it cannot be read or is no log.
  explicit LogReader(const std::string& path, LogReaderOptions options = {});
  ~LogReader();
  LogReader(LogReader&&) noexcept;
  LogReader& operator=(LogReader&&) noexcept;

  /// The next message (CARMEN: file order; bags: time order), or nullopt at the end.
  std::optional<SensorMessage> next();
  double progress() const;
  const std::string& path() const;
  LogFormat format() const { return format_; }
  /// The reader behind: exactly one is set.
  const CarmenReader* carmen() const { return carmen_.get(); }
  const BagLogReader* bag() const { return bag_.get(); }
  /// CARMEN's counters; zeros for a bag (read in time order, nothing skipped or repaired).
  CarmenStats stats() const;

 private:
  LogFormat format_;
  std::unique_ptr<CarmenReader> carmen_;
  std::unique_ptr<BagLogReader> bag_;
  // With an odometry time offset: the whole log, shifted, and how many messages were given out.
  std::optional<std::vector<SensorMessage>> shifted_;
  std::size_t served_ = 0;
  std::optional<SensorMessage> next_from_file();
};

/// Every message left in `reader`; `progress(fraction, messages so far)` every 4096 messages.
std::vector<SensorMessage> read_all(LogReader& reader,
                                    const std::function<void(double, std::size_t)>& progress = {});

}  // namespace slam2d
