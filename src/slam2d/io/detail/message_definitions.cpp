// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/detail/message_definitions.hpp"

#include <map>
#include <set>
#include <vector>

#include "slam2d/core/error.hpp"

namespace slam2d::detail {
namespace {

struct Definition {
  std::string_view fields;
  std::vector<std::string_view> uses;  // the types its fields name, "package/Type"
};

const std::map<std::string_view, Definition>& definitions() {
  static const std::map<std::string_view, Definition> known = {
      {"builtin_interfaces/Time", {"int32 sec\nuint32 nanosec\n", {}}},
      {"std_msgs/Header", {"builtin_interfaces/Time stamp\nstring frame_id\n", {"builtin_interfaces/Time"}}},
      {"geometry_msgs/Point", {"float64 x\nfloat64 y\nfloat64 z\n", {}}},
      {"geometry_msgs/Vector3", {"float64 x\nfloat64 y\nfloat64 z\n", {}}},
      {"geometry_msgs/Quaternion", {"float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n", {}}},
      {"geometry_msgs/Pose",
       {"geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
        {"geometry_msgs/Point", "geometry_msgs/Quaternion"}}},
      {"geometry_msgs/PoseWithCovariance", {"geometry_msgs/Pose pose\nfloat64[36] covariance\n", {"geometry_msgs/Pose"}}},
      {"geometry_msgs/Twist", {"geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n", {"geometry_msgs/Vector3"}}},
      {"geometry_msgs/TwistWithCovariance", {"geometry_msgs/Twist twist\nfloat64[36] covariance\n", {"geometry_msgs/Twist"}}},
      {"geometry_msgs/Transform",
       {"geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
        {"geometry_msgs/Vector3", "geometry_msgs/Quaternion"}}},
      {"geometry_msgs/TransformStamped",
       {"std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
        {"std_msgs/Header", "geometry_msgs/Transform"}}},
      {"geometry_msgs/PoseStamped", {"std_msgs/Header header\ngeometry_msgs/Pose pose\n", {"std_msgs/Header", "geometry_msgs/Pose"}}},
      {"geometry_msgs/PoseArray", {"std_msgs/Header header\ngeometry_msgs/Pose[] poses\n", {"std_msgs/Header", "geometry_msgs/Pose"}}},
      {"tf2_msgs/TFMessage", {"geometry_msgs/TransformStamped[] transforms\n", {"geometry_msgs/TransformStamped"}}},
      {"sensor_msgs/LaserScan",
       {"std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\nfloat32 time_increment\n"
        "float32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n",
        {"std_msgs/Header"}}},
      {"sensor_msgs/Imu",
       {"std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
        "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
        "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
        {"std_msgs/Header", "geometry_msgs/Quaternion", "geometry_msgs/Vector3"}}},
      {"sensor_msgs/PointField",
       {"uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\n"
        "uint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
        {}}},
      {"sensor_msgs/PointCloud2",
       {"std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\nbool is_bigendian\n"
        "uint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
        {"std_msgs/Header", "sensor_msgs/PointField"}}},
      {"nav_msgs/Odometry",
       {"std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
        "geometry_msgs/TwistWithCovariance twist\n",
        {"std_msgs/Header", "geometry_msgs/PoseWithCovariance", "geometry_msgs/TwistWithCovariance"}}},
      {"nav_msgs/MapMetaData",
       {"builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\ngeometry_msgs/Pose origin\n",
        {"builtin_interfaces/Time", "geometry_msgs/Pose"}}},
      {"nav_msgs/OccupancyGrid",
       {"std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n", {"std_msgs/Header", "nav_msgs/MapMetaData"}}},
      {"nav_msgs/Path", {"std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n", {"std_msgs/Header", "geometry_msgs/PoseStamped"}}},
  };
  return known;
}

const Definition& definition(std::string_view type, RosVersion version) {
  static const Definition kRos1Header = {"uint32 seq\ntime stamp\nstring frame_id\n", {}};
  if (version == RosVersion::kRos1 && type == "std_msgs/Header") return kRos1Header;
  const auto found = definitions().find(type);
  if (found == definitions().end()) throw Error("no ROS 2 definition of " + std::string(type) + " in slam2d");
  return found->second;
}

// The types `type` uses, directly or not, each once, in the order first met.
void collect_uses(std::string_view type, RosVersion version, std::vector<std::string_view>& order,
                  std::set<std::string_view>& seen) {
  for (std::string_view used : definition(type, version).uses) {
    if (!seen.insert(used).second) continue;
    order.push_back(used);
    collect_uses(used, version, order, seen);
  }
}

}  // namespace

std::string message_definition(std::string_view type, RosVersion version) {
  // "sensor_msgs/msg/LaserScan" -> "sensor_msgs/LaserScan", the form the definitions use.
  std::string name(type);
  if (const std::size_t at = name.find("/msg/"); at != std::string::npos) name.erase(at, 4);
  std::string text(definition(name, version).fields);
  std::vector<std::string_view> order;
  std::set<std::string_view> seen;
  collect_uses(name, version, order, seen);
  for (std::string_view used : order) {
    text += "================================================================================\nMSG: ";
    text.append(used).append("\n").append(definition(used, version).fields);
  }
  return text;
}

}  // namespace slam2d::detail
