#pragma once
// Real scans for the micro benchmarks: the first scans of $SLAM2D_DATA/<log>/<log>.clf.gz
// (default ../shared/data), read once. Empty when the data is absent; benchmarks then skip.

#include <cstddef>
#include <string>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d::bench {

struct LoggedScan {
  LaserScan scan;
  SE2 odom_pose;   // T_odom_robot at the scan
  SE2 laser_pose;  // the log's own pose of the scan
};

/// Up to `count` front-laser scans of the log, in file order (cached per log name).
const std::vector<LoggedScan>& logged_scans(const std::string& log = "intel", std::size_t count = 2000);

/// The valid end points of scan i in its sensor frame, in beam order.
PointCloud2 sensor_cloud(const LaserScan& scan);

}  // namespace slam2d::bench
