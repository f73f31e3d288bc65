// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/run_mcap.hpp"

#include <cstring>
#include <map>
#include <optional>

#include "slam2d/core/error.hpp"
#include "slam2d/io/detail/cdr.hpp"
#include "slam2d/io/detail/message_definitions.hpp"
#include "slam2d/io/mcap_writer.hpp"

namespace slam2d {
namespace {

using detail::CdrWriter;

constexpr const char* kMapFrame = "map";
constexpr const char* kBaseFrame = "base_link";
constexpr const char* kLaserFrame = "laser";

std::vector<std::uint8_t> occupancy_grid(const OccupancyMap& map, double stamp) {
  CdrWriter out;
  out.header(stamp, kMapFrame);
  out.time(stamp).put(static_cast<float>(map.resolution));  // info: map_load_time, resolution
  out.put(static_cast<std::uint32_t>(map.width)).put(static_cast<std::uint32_t>(map.height)).pose(map.origin);
  out.count(map.cells.size()).raw(reinterpret_cast<const std::uint8_t*>(map.cells.data()), map.cells.size());
  return out.take();
}

void pose_stamped(CdrWriter& out, double stamp, const SE2& pose) { out.header(stamp, kMapFrame).pose(pose); }

std::vector<std::uint8_t> path_message(const Trajectory& trajectory) {
  CdrWriter out;
  out.header(trajectory.empty() ? 0.0 : trajectory.back().stamp, kMapFrame).count(trajectory.size());
  for (const StampedPose& stamped : trajectory) pose_stamped(out, stamped.stamp, stamped.pose);
  return out.take();
}

std::vector<std::uint8_t> points_in_map(const LaserScan& scan, const SE2& T_map_robot) {
  const ScanPoints points = to_point_cloud(scan, ScanFrame::kRobot);
  const std::size_t n = points.cloud.size();
  CdrWriter out;
  out.header(scan.stamp, kMapFrame).put(std::uint32_t{1}).put(static_cast<std::uint32_t>(n));  // height, width
  out.count(3);
  for (std::uint32_t i = 0; i < 3; ++i) {  // PointField: name, offset, datatype FLOAT32 (7), count
    out.string(std::string(1, static_cast<char>('x' + i))).put(4 * i).put(std::uint8_t{7}).put(std::uint32_t{1});
  }
  out.put(std::uint8_t{0}).put(std::uint32_t{12}).put(static_cast<std::uint32_t>(12 * n));  // is_bigendian, steps
  std::vector<std::uint8_t> data(12 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d p = T_map_robot * points.cloud.points[i];
    const float xyz[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()), 0.0f};
    std::memcpy(data.data() + 12 * i, xyz, sizeof(xyz));
  }
  out.count(data.size()).raw(data.data(), data.size()).put(std::uint8_t{1});  // is_dense
  return out.take();
}

}  // namespace

struct RunMcapWriter::Impl {
  explicit Impl(const std::string& path) : writer(path) {}

  std::uint16_t channel(const std::string& topic, const std::string& type) {
    auto schema = schemas.find(type);
    if (schema == schemas.end()) {
      schema = schemas.emplace(type, writer.add_schema(type, "ros2msg", detail::message_definition(type, detail::RosVersion::kRos2))).first;
    }
    return writer.add_channel(topic, schema->second, "cdr");
  }

  McapWriter writer;
  std::map<std::string, std::uint16_t> schemas;
  std::uint16_t map_channel = 0, path_channel = 0, pose = 0, tf = 0, tf_static = 0, scan = 0, scan_map = 0;
  std::optional<double> first_stamp;
  double last_stamp = 0.0;
  std::optional<SE2> mounting;
};

RunMcapWriter::RunMcapWriter(const std::string& path) : impl_(std::make_unique<Impl>(path)) {
  Impl& s = *impl_;
  s.map_channel = s.channel("/map", "nav_msgs/msg/OccupancyGrid");
  s.path_channel = s.channel("/path", "nav_msgs/msg/Path");
  s.pose = s.channel("/pose", "geometry_msgs/msg/PoseStamped");
  s.tf = s.channel("/tf", "tf2_msgs/msg/TFMessage");
  s.tf_static = s.channel("/tf_static", "tf2_msgs/msg/TFMessage");
  s.scan = s.channel("/scan", "sensor_msgs/msg/LaserScan");
  s.scan_map = s.channel("/scan_map", "sensor_msgs/msg/PointCloud2");
}

RunMcapWriter::~RunMcapWriter() = default;

void RunMcapWriter::add_scan(const LaserScan& scan, const SE2& T_map_robot) {
  Impl& s = *impl_;
  const std::uint64_t t = seconds_to_nanoseconds(scan.stamp);
  if (!s.mounting || s.mounting->vector() != scan.T_robot_sensor.vector()) {
    s.mounting = scan.T_robot_sensor;
    s.writer.write(s.tf_static, t, detail::encode_cdr(DecodedTransforms{true, {{scan.stamp, kBaseFrame, kLaserFrame, *s.mounting}}}));
  }
  if (!s.first_stamp) s.first_stamp = scan.stamp;
  s.last_stamp = scan.stamp;
  CdrWriter pose;
  pose_stamped(pose, scan.stamp, T_map_robot);
  s.writer.write(s.pose, t, pose.take());
  s.writer.write(s.tf, t, detail::encode_cdr(DecodedTransforms{false, {{scan.stamp, kMapFrame, kBaseFrame, T_map_robot}}}));
  s.writer.write(s.scan, t, detail::encode_cdr(DecodedScan{kLaserFrame, scan}));
  s.writer.write(s.scan_map, t, points_in_map(scan, T_map_robot));
}

void RunMcapWriter::commit(const OccupancyMap& map, const Trajectory& trajectory) {
  Impl& s = *impl_;
  const double first = s.first_stamp.value_or(trajectory.empty() ? 0.0 : trajectory.front().stamp);
  const double last = s.first_stamp ? s.last_stamp : first;
  s.writer.write(s.map_channel, seconds_to_nanoseconds(first), occupancy_grid(map, first));
  s.writer.write(s.path_channel, seconds_to_nanoseconds(last), path_message(trajectory));
  s.writer.commit();
}

}  // namespace slam2d
