// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A sensor log (core/sensor_log.hpp) written in any format slam2d reads: CARMEN, a ROS 1 bag, an
// MCAP file or a rosbag2 folder (MCAP storage). What `slam2d convert` and `slam2d perturb` write.
//
// A bag gets the topics a ROS driver stack publishes, in the frames of BagLayout:
//   /scan        sensor_msgs/LaserScan, frame laser (RLASER scans: /scan_rear, frame laser_rear)
//   /odom        nav_msgs/Odometry odom -> base_link, and the same transform on /tf; from the
//                log's odometry readings, or, in a log without any, from each scan's odometry pose
//   /tf_static   base_link -> laser: each laser's mounting (T_robot_sensor), again when it changes
//   /imu         sensor_msgs/Imu
// ROS 1 bags keep the log's order (its recording order); ROS 2 formats are written in time order.
// A bag has no type slam2d reads for CARMEN's TRUEPOS, and CARMEN no line for an IMU reading: those
// messages are counted in the report, not written. A bag's LaserScan becomes CARMEN's ROBOTLASER1
// (RAWLASER1 without poses), which declares its angles, maximum range and mounting.

#include <cstddef>
#include <string>
#include <vector>

#include "slam2d/core/sensor_log.hpp"
#include "slam2d/io/log_reader.hpp"

namespace slam2d {

struct BagLayout {
  std::string scan_topic = "/scan";
  std::string rear_scan_topic = "/scan_rear";
  std::string odom_topic = "/odom";
  std::string imu_topic = "/imu";
  std::string base_frame = "base_link";
  std::string odom_frame = "odom";
  std::string laser_frame = "laser";
  std::string rear_laser_frame = "laser_rear";
};

/// What was written.
struct LogWriteReport {
  std::size_t scans = 0;
  std::size_t odometry = 0;      // odometry readings written (bags: Odometry messages)
  std::size_t imu = 0;
  std::size_t true_poses = 0;
  std::size_t not_written = 0;   // TRUEPOS in a bag, IMU in CARMEN
};

/// The format `path` asks for by its name: ".bag" ROS 1, ".mcap" MCAP, a name ending in '/' or
/// without an extension a rosbag2 folder, anything else CARMEN (".gz": gzip).
LogFormat log_format_for_output(const std::string& path);
/// "carmen", "ros1", "mcap", "rosbag2" (log_format_name's names); Error for another.
LogFormat parse_log_format(const std::string& name);

/// Writes `messages` at `path` in `format`, atomically. `comments` go into a CARMEN log's header
/// (bags have no place for them). Throws Error("PATH: ...") on a message the format cannot hold.
LogWriteReport write_log(const std::string& path, LogFormat format, const std::vector<SensorMessage>& messages,
                         const std::vector<std::string>& comments = {}, const BagLayout& layout = {});

}  // namespace slam2d
