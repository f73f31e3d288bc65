// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/bag_log.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

constexpr std::size_t kOdometryWindow = 64;     // recent readings kept for the interpolation
constexpr std::size_t kMaxPendingScans = 256;  // scans held waiting for the odometry to pass them
constexpr std::size_t kNeighbours = 8;          // readings each side of a scan in the file searched by stamp
constexpr const char* kLaserScan = "sensor_msgs/LaserScan";
constexpr const char* kOdometry = "nav_msgs/Odometry";
constexpr const char* kImu = "sensor_msgs/Imu";
constexpr const char* kTf = "tf2_msgs/TFMessage";

// The topic `wanted` names (checked to exist and to have `type`), or the one topic of `type`;
// "" when there is none and `required` is false.
std::string pick(const std::string& path, const std::vector<BagTopic>& topics, const std::string& type,
                 const std::string& wanted, const char* option, bool required) {
  std::vector<std::string> candidates;
  for (const BagTopic& topic : topics) {
    if (ros_type_name(topic.type) == type) candidates.push_back(topic.name);
  }
  std::string list;
  for (const std::string& name : candidates) list += (list.empty() ? "" : ", ") + name;
  if (!wanted.empty()) {
    for (const BagTopic& topic : topics) {
      if (topic.name != wanted) continue;
      check(ros_type_name(topic.type) == type, path + ": topic " + wanted + " is " + topic.type + ", not " + type);
      return wanted;
    }
    throw Error(path + ": no topic " + wanted + " (" + type + " topics: " + (list.empty() ? "none" : list) + ")");
  }
  if (candidates.size() == 1) return candidates.front();
  if (candidates.empty()) {
    check(!required, path + ": no " + type + " topic in the bag");
    return "";
  }
  throw Error(path + ": several " + type + " topics (" + list + "): choose one with " + option);
}

bool has_topic(const std::vector<BagTopic>& topics, const std::string& name, const char* type) {
  return std::any_of(topics.begin(), topics.end(),
                     [&](const BagTopic& topic) { return topic.name == name && ros_type_name(topic.type) == type; });
}

}  // namespace

std::string ros_type_name(const std::string& type) {
  const std::size_t at = type.find("/msg/");
  return at == std::string::npos ? type : type.substr(0, at) + "/" + type.substr(at + 5);
}

BagChoice choose_topics(const std::string& path, const std::vector<BagTopic>& topics, const BagSelection& selection) {
  BagChoice choice;
  choice.scan_topic = pick(path, topics, kLaserScan, selection.scan_topic, "--scan-topic", true);
  choice.odom_topic = pick(path, topics, kOdometry, selection.odom_topic, "--odom-topic", false);
  if (choice.odom_topic.empty() && has_topic(topics, "/tf", kTf)) choice.odom_topic = "/tf";  // odom -> base
  choice.imu_topic = pick(path, topics, kImu, selection.imu_topic, "--imu-topic", false);
  choice.base_frame = selection.base_frame;
  choice.odom_frame = selection.odom_frame;
  return choice;
}

BagLogReader::BagLogReader(std::unique_ptr<BagSource> source, BagSelection selection, ScanGeometryOverrides geometry)
    : source_(std::move(source)),
      choice_(choose_topics(source_->path(), source_->topics(), selection)),
      geometry_(geometry),
      scan_odometry_(selection.scan_odometry) {
  check_overrides(geometry_, source_->path());
  wanted_ = {choice_.scan_topic};
  if (!choice_.odom_topic.empty()) wanted_.push_back(choice_.odom_topic);
  if (!choice_.imu_topic.empty()) wanted_.push_back(choice_.imu_topic);
  if (has_topic(source_->topics(), "/tf_static", kTf)) wanted_.push_back("/tf_static");
  if (choice_.odom_topic == "/tf" && (choice_.base_frame.empty() || choice_.odom_frame.empty())) {
    if (choice_.base_frame.empty()) choice_.base_frame = "base_link";
    if (choice_.odom_frame.empty()) choice_.odom_frame = "odom";
  }
}

BagLogReader::~BagLogReader() = default;

const std::string& BagLogReader::path() const { return source_->path(); }
const std::vector<BagTopic>& BagLogReader::topics() const { return source_->topics(); }
double BagLogReader::progress() const { return source_->progress(); }

std::optional<SensorMessage> BagLogReader::next() {
  while (ready_.empty() && !finished_) read_more();
  if (ready_.empty()) return std::nullopt;
  SensorMessage message = std::move(ready_.front());
  ready_.pop_front();
  return message;
}

void BagLogReader::read_more() {
  std::optional<DecodedRecord> record = source_->next(wanted_);
  if (record) {
    take(std::move(*record));
    return;
  }
  // The end: scans after the last odometry reading hold its pose.
  release_scans_up_to(std::numeric_limits<double>::infinity());
  finished_ = true;
  const std::vector<std::string> source_warnings = source_->warnings();
  warnings_.insert(warnings_.end(), source_warnings.begin(), source_warnings.end());
  if (choice_.base_frame.empty()) choice_.base_frame = "base_link";
  if (choice_.odom_topic.empty() || !has_odometry_) {
    warnings_.push_back(path() + ": no odometry in the bag (no Odometry topic, no odom -> base on /tf)");
  }
  if (!choice_.laser_frame.empty() && choice_.laser_frame != choice_.base_frame && !choice_.T_base_laser) {
    warnings_.push_back(path() + ": no static transform " + choice_.base_frame + " -> " + choice_.laser_frame +
                        ": the laser is taken at the robot's origin");
  }
}

void BagLogReader::take(DecodedRecord record) {
  if (auto* scan = std::get_if<DecodedScan>(&record.message)) {
    if (choice_.laser_frame.empty()) {
      choice_.laser_frame = scan->frame_id;
      resolve_mounting();
      check_declared_geometry(scan->scan);
    }
    pending_scans_.push_back({std::move(*scan), record.index, odometry_seen_});
    if (!has_odometry_ && choice_.odom_topic.empty()) release_scans_up_to(std::numeric_limits<double>::infinity());
    return;
  }
  if (auto* transforms = std::get_if<DecodedTransforms>(&record.message)) {
    for (const DecodedTransform& transform : transforms->transforms) {
      if (transforms->is_static || record.topic == "/tf_static") {
        add_static(transform);
      } else if (record.topic == choice_.odom_topic && transform.parent == choice_.odom_frame &&
                 transform.child == choice_.base_frame) {
        const OdometryReading reading{.stamp = transform.stamp, .pose = transform.T_parent_child};
        add_odometry(reading);
        ready_.push_back(OdometryMessage{reading, record.index});
      }
    }
    return;
  }
  if (const auto* imu = std::get_if<DecodedImu>(&record.message)) {
    ready_.push_back(ImuMessage{imu->reading, record.index});
    return;
  }
  if (auto* odometry = std::get_if<DecodedOdometry>(&record.message)) {
    if (choice_.base_frame.empty()) choice_.base_frame = odometry->child_frame_id.empty() ? "base_link" : odometry->child_frame_id;
    if (choice_.odom_frame.empty()) choice_.odom_frame = odometry->frame_id.empty() ? "odom" : odometry->frame_id;
    add_odometry(odometry->reading);
    ready_.push_back(OdometryMessage{odometry->reading, record.index});
  }
}

void BagLogReader::check_declared_geometry(const LaserScan& scan) {
  // An even beam count spread over exactly 180 deg, first beam at -90 deg: what a converter writes
  // for CARMEN's 180 (360) beams of 1 (0.5) deg, which span 179 (179.5) deg (the Intel bag).
  constexpr double kPi = std::numbers::pi;
  constexpr double kTolerance = 1e-5;  // rad: the declared angles are float32
  const std::size_t n = scan.size();
  if (geometry_.any() || n < 2 || n % 2 != 0) return;
  if (std::abs(scan.angle_max() - scan.angle_min - kPi) > kTolerance || std::abs(scan.angle_min + kPi / 2) > kTolerance) return;
  warnings_.push_back(path() + ": warning: the scans declare " + std::to_string(n) +
                      " beams over exactly 180 deg; a scanner with an even beam count over a half turn steps 180/" +
                      std::to_string(n) + " deg (CARMEN's convention): if this bag was converted from a CARMEN log, "
                      "--fov 180 reads it so (docs/bags.md)");
}

void BagLogReader::add_odometry(const OdometryReading& reading) {
  odometry_.push_back(reading);
  ++odometry_seen_;
  if (odometry_.size() > kOdometryWindow) odometry_.pop_front();
  latest_odometry_stamp_ = has_odometry_ ? std::max(latest_odometry_stamp_, reading.stamp) : reading.stamp;
  has_odometry_ = true;
  release_scans_up_to(latest_odometry_stamp_);
}

void BagLogReader::add_static(const DecodedTransform& transform) {
  static_transforms_.push_back(transform);
  resolve_mounting();
}

void BagLogReader::resolve_mounting() {
  if (choice_.laser_frame.empty() || choice_.T_base_laser) return;
  const std::string base = choice_.base_frame.empty() ? "base_link" : choice_.base_frame;
  for (const DecodedTransform& known : static_transforms_) {  // one link, either direction
    if (known.parent == base && known.child == choice_.laser_frame) choice_.T_base_laser = known.T_parent_child;
    if (known.child == base && known.parent == choice_.laser_frame) choice_.T_base_laser = known.T_parent_child.inverse();
  }
}

std::optional<SE2> BagLogReader::odometry_at(double stamp, std::size_t readings_before) const {
  if (odometry_.empty()) return std::nullopt;
  const std::size_t first = odometry_seen_ - odometry_.size();  // the bag index of odometry_.front()
  const auto reading = [&](std::size_t bag_index) -> const OdometryReading& { return odometry_[bag_index - first]; };
  const bool has_previous = readings_before > first && readings_before <= odometry_seen_;
  const bool has_next = readings_before >= first && readings_before < odometry_seen_;
  if (scan_odometry_ == OdometryAtScan::kLatest) {
    if (has_previous) return reading(readings_before - 1).pose;
    return readings_before <= first ? odometry_.front().pose : odometry_.back().pose;
  }
  // The readings recorded just before and just after the scan, when their stamps bracket it: the
  // recording order is the order things happened, even where stamps are wrong (the Intel log's clock
  // steps back up to 0.9 s: a reading from before the step can carry a later stamp than a scan after it).
  if (has_previous && has_next) {
    const OdometryReading& previous = reading(readings_before - 1);
    const OdometryReading& next = reading(readings_before);
    if (previous.stamp <= stamp && stamp <= next.stamp) {
      return next.stamp > previous.stamp
                 ? interpolate(previous.pose, next.pose, (stamp - previous.stamp) / (next.stamp - previous.stamp))
                 : previous.pose;
    }
  }
  // Otherwise (a scan recorded a little before or after the readings around its stamp, as topics
  // interleave), the readings just before and just after its stamp among its neighbours in the bag.
  const std::size_t low = std::max(first, readings_before > kNeighbours ? readings_before - kNeighbours : std::size_t{0});
  const std::size_t high = std::min(odometry_seen_, readings_before + kNeighbours);
  const OdometryReading* before = nullptr;
  const OdometryReading* after = nullptr;
  for (std::size_t i = low; i < high; ++i) {
    const OdometryReading& r = reading(i);
    if (r.stamp <= stamp && (before == nullptr || r.stamp >= before->stamp)) before = &r;
    if (r.stamp >= stamp && (after == nullptr || r.stamp < after->stamp)) after = &r;
  }
  if (before == nullptr && after == nullptr) {  // no neighbour left: the nearest reading in the bag
    return readings_before <= first ? odometry_.front().pose : odometry_.back().pose;
  }
  if (before == nullptr) return after->pose;
  if (after == nullptr || !(after->stamp > before->stamp)) return before->pose;
  return interpolate(before->pose, after->pose, (stamp - before->stamp) / (after->stamp - before->stamp));
}

void BagLogReader::release_scans_up_to(double stamp) {
  // In the bag's order: a scan waits for the odometry to pass its stamp (so that it can be
  // interpolated) and for the reading recorded after it, and never holds more than
  // kMaxPendingScans behind it.
  while (!pending_scans_.empty() &&
         ((pending_scans_.front().scan.scan.stamp <= stamp && pending_scans_.front().readings_before < odometry_seen_) ||
          std::isinf(stamp) || pending_scans_.size() > kMaxPendingScans)) {
    ready_.push_back(to_laser(pending_scans_.front()));
    pending_scans_.pop_front();
  }
}

LaserMessage BagLogReader::to_laser(const PendingScan& pending) const {
  const DecodedScan& scan = pending.scan;
  LaserMessage laser;
  laser.type = "LaserScan";
  laser.scan = scan.scan;
  apply_overrides(laser.scan, geometry_);
  laser.scan.T_robot_sensor = choice_.T_base_laser.value_or(SE2());
  laser.field_of_view = laser.scan.angle_max() - laser.scan.angle_min;  // as the message declares it, or overridden
  const std::optional<SE2> odom = odometry_at(scan.scan.stamp, pending.readings_before);
  laser.has_poses = odom.has_value();
  laser.odom_pose = odom.value_or(SE2());
  laser.laser_pose = laser.odom_pose * laser.scan.T_robot_sensor;
  laser.line = pending.index;
  return laser;
}

}  // namespace slam2d
