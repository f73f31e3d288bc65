// SPDX-License-Identifier: BSD-3-Clause
// Map a log: graph SLAM over a CARMEN log, the trajectory written as "t x y theta" lines.
//   map_log LOG.clf[.gz] TRAJECTORY.txt
#include <cstdio>
#include <exception>
#include <variant>

#include <slam2d/io/carmen.hpp>
#include <slam2d/io/trajectory_io.hpp>
#include <slam2d/slam/graph/graph_slam.hpp>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s LOG TRAJECTORY\n", argv[0]);
    return 2;
  }
  try {
    slam2d::CarmenReader reader(argv[1]);
    slam2d::GraphSlam slam;
    while (auto message = reader.next()) {
      if (const auto* laser = std::get_if<slam2d::LaserMessage>(&*message)) slam.add_scan(laser->scan, laser->odom_pose);
    }
    slam.finish();
    const slam2d::Trajectory trajectory = slam.trajectory();
    slam2d::write_trajectory(argv[2], trajectory);
    std::printf("%zu scans, %zu keyframes; trajectory in %s\n", trajectory.size(), slam.keyframes().size(), argv[2]);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "map_log: %s\n", error.what());
    return 1;
  }
  return 0;
}
