// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A run's results as an MCAP file that Foxglove (and `ros2 bag play`) opens: ROS 2 types in CDR,
// "ros2msg" schemas. What `slam2d map --mcap` and `slam2d localize --mcap` write:
//   /map        nav_msgs/OccupancyGrid, frame map: the map, once, at the first scan's time
//   /path       nav_msgs/Path, frame map: the whole trajectory, once, at the last scan's time
//   /pose       geometry_msgs/PoseStamped, frame map: the robot's pose at each scan
//   /tf         tf2_msgs/TFMessage: map -> base_link at each scan
//   /tf_static  base_link -> laser: the laser's mounting
//   /scan       sensor_msgs/LaserScan, frame laser: each scan as read
//   /scan_map   sensor_msgs/PointCloud2, frame map: each scan's valid end points in the map frame
//               (fields x, y, z as float32), so that a viewer needs no transform tree
// Written atomically, like every output.

#include <memory>
#include <string>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/trajectory.hpp"

namespace slam2d {

class RunMcapWriter {
 public:
  explicit RunMcapWriter(const std::string& path);
  ~RunMcapWriter();  // without commit(): nothing at the path
  RunMcapWriter(const RunMcapWriter&) = delete;
  RunMcapWriter& operator=(const RunMcapWriter&) = delete;

  /// One scan and the robot's pose at it (T_map_robot), in time order.
  void add_scan(const LaserScan& scan, const SE2& T_map_robot);
  /// Writes the map and the path (the trajectory of the robot) and finishes the file.
  void commit(const OccupancyMap& map, const Trajectory& trajectory);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam2d
