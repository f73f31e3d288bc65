// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ROS 1 bags (format v2.0, http://wiki.ros.org/Bags/Format/2.0): uncompressed, bz2 and lz4 chunks,
// read through the bag's index. Decodes sensor_msgs/LaserScan, nav_msgs/Odometry,
// tf2_msgs/TFMessage and sensor_msgs/Imu into the structs of bag_source.hpp.

#include <memory>
#include <string>

#include "slam2d/io/bag_source.hpp"

namespace slam2d {

/// True when the file starts with the ROS 1 bag v2.0 magic "#ROSBAG V2.0\n" (false when it cannot
/// be read).
bool is_ros1_bag(const std::string& path);

/// Opens a ROS 1 bag and reads its index (connections, chunk infos, each chunk's index data).
/// Messages come out in the recording order of the file (rosbag writes them as they arrive): not
/// sorted by stamp, since a log whose stamps step back (the Intel bag: scans up to 0.9 s out of
/// order) would be scrambled. Each chunk is decompressed once, when first needed, and dropped after
/// its last wanted message.
/// A bag without an index (a recording that was killed: index_pos 0, or past the end of a file cut
/// short) is read in one pass over its chunks, as `rosbag reindex` would, in the same order; a last
/// record cut short is left out; both with a warning (BagSource::warnings).
/// Throws Error("PATH: ...") for a file that is not a v2.0 bag or whose records are inconsistent.
std::unique_ptr<BagSource> open_ros1_bag(const std::string& path);

}  // namespace slam2d
