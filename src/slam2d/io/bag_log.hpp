// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Any bag (ROS 1, MCAP, rosbag2) as the format-neutral sensor log (core/sensor_log.hpp): the one
// assembly behind every container reader (io/bag_source.hpp).
//
// - Topics: the laser scans come from the one LaserScan topic, the odometry from the one Odometry
//   topic (or, without one, from the odom -> base transforms on /tf), the IMU from the one Imu
//   topic; each is automatic when the bag has exactly one candidate, else BagSelection names it,
//   and an ambiguous or missing choice is an Error naming the candidates.
// - The laser's mounting T_robot_sensor: base frame -> the scan's frame_id through the static
//   transforms (/tf_static; a chain of them, either direction). Unknown: the robot's origin,
//   with a warning.
// - Each scan's odometry pose (LaserMessage::odom_pose; CARMEN's FLASER carries it, a bag carries
//   the odometry on its own topic): by default interpolated at the scan's stamp between the readings
//   recorded just before and after it, when their stamps bracket it; else between the readings just
//   before and after its stamp among its neighbours in the bag's order (held at the first/last
//   reading outside their span). Or (OdometryAtScan::kLatest) the latest reading recorded before it.
// - The scans' geometry as the messages declare it, or as ScanGeometryOverrides says (a converter
//   that declared 180 deg for a 179 deg sensor).
// - Ranges as published: NaN, +-inf and values outside [range_min, range_max] are "no return"
//   (LaserScan::is_valid), never errors.
// - IMU readings (ImuMessage) from the Imu topic, as they come.
// Messages come out in the bag's order (each reader's: see its header), each scan once the
// odometry has passed its stamp.

#include <cstddef>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "slam2d/core/sensor_log.hpp"
#include "slam2d/io/bag_source.hpp"
#include "slam2d/io/scan_geometry.hpp"

namespace slam2d {

/// Each scan's odometry pose: interpolated at its stamp (what tf does), or the latest reading
/// recorded before it (what CARMEN's logger wrote into FLASER: for logs whose stamps are less
/// trustworthy than their recording order).
enum class OdometryAtScan { kInterpolated, kLatest };

/// Which topics and frames make the sensor log; empty: automatic (unambiguous) choice.
struct BagSelection {
  OdometryAtScan scan_odometry = OdometryAtScan::kInterpolated;
  std::string scan_topic = {};
  std::string odom_topic = {};
  std::string imu_topic = {};
  std::string base_frame = {};  // default: the odometry's child frame, else base_link
  std::string odom_frame = {};  // default: the odometry's frame, else odom
};

/// What the assembly chose and found (for `slam2d info` and the warnings).
struct BagChoice {
  std::string scan_topic = {};
  std::string odom_topic = {};       // the Odometry topic, or "/tf" when the odometry is odom -> base on /tf; empty: none
  std::string imu_topic = {};        // empty: none
  std::string base_frame = {};
  std::string odom_frame = {};
  std::string laser_frame;      // the scans' frame_id (of the first scan)
  std::optional<SE2> T_base_laser;  // from the static transforms; nullopt until found (or never)
};

/// The ROS type name without ROS 2's "/msg/" ("sensor_msgs/msg/LaserScan" -> "sensor_msgs/LaserScan").
std::string ros_type_name(const std::string& type);

/// Decides the topics of `topics` under `selection` (see above). Throws Error naming the bag.
BagChoice choose_topics(const std::string& path, const std::vector<BagTopic>& topics, const BagSelection& selection);

class BagLogReader {
 public:
  explicit BagLogReader(std::unique_ptr<BagSource> source, BagSelection selection = {},
                        ScanGeometryOverrides geometry = {});
  ~BagLogReader();

  /// The next message in time order, or nullopt at the end.
  std::optional<SensorMessage> next();
  double progress() const;
  const std::string& path() const;
  const std::vector<BagTopic>& topics() const;
  const BagChoice& choice() const { return choice_; }
  /// What the assembly could not decide (no mounting found, no odometry, ...); complete at the end.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  void read_more();
  void take(DecodedRecord record);
  void release_scans_up_to(double stamp);
  struct PendingScan {
    DecodedScan scan;
    std::size_t index = 0;            // in the bag's order
    std::size_t readings_before = 0;  // odometry readings before it in the bag's order
  };
  LaserMessage to_laser(const PendingScan& pending) const;
  std::optional<SE2> odometry_at(double stamp, std::size_t readings_before) const;
  void add_odometry(const OdometryReading& reading);
  void add_static(const DecodedTransform& transform);
  void resolve_mounting();  // T_base_laser from the static transforms seen so far
  void check_declared_geometry(const LaserScan& scan);  // a warning for a converter's 180 deg

  std::unique_ptr<BagSource> source_;
  BagChoice choice_;
  ScanGeometryOverrides geometry_;
  OdometryAtScan scan_odometry_;
  std::vector<std::string> wanted_;
  std::vector<DecodedTransform> static_transforms_;
  std::deque<OdometryReading> odometry_;  // the recent readings, in the bag's order
  std::size_t odometry_seen_ = 0;         // readings so far
  double latest_odometry_stamp_ = 0.0;    // the largest odometry stamp so far
  std::deque<PendingScan> pending_scans_;  // scans waiting for the next reading
  std::deque<SensorMessage> ready_;
  bool finished_ = false;
  bool has_odometry_ = false;
  std::vector<std::string> warnings_;
};

}  // namespace slam2d
