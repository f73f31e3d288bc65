// SPDX-License-Identifier: BSD-3-Clause
// Stamps that carry no speed (core/odometry_guard.hpp, "the step test"): the SLAM-corrected Örebro
// log stamps every scan 0 and its scans lie up to 3.3 m apart; the robustness benchmark gives each
// scan its index (1 s a scan). With the speed bounds alone 11 of its 236 increments (227 with the
// stamps as logged) were taken for jumps and graph SLAM scored 14.3 m ATE. The laser lines'
// odometry is the corrected trajectory itself, so each method is scored against it.

#include <gtest/gtest.h>

#include <iostream>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/eval/ate.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

// The front-laser scans; with index_stamps, each stamped with its index (the benchmark's stamps).
std::vector<LaserMessage> orebro_scans(const std::filesystem::path& data, bool index_stamps) {
  std::vector<LaserMessage> scans;
  CarmenReader reader((data / "carmen-corrected/orebro-corrected.log.gz").string());
  while (auto message = reader.next()) {
    auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type != "FLASER") continue;
    if (index_stamps) laser->scan.stamp = static_cast<double>(scans.size());
    scans.push_back(std::move(*laser));
  }
  return scans;
}

// Poses stamped with their index, so that stamps all alike still associate.
Trajectory by_index(const Trajectory& trajectory) {
  Trajectory indexed;
  for (std::size_t i = 0; i < trajectory.size(); ++i) indexed.push_back(static_cast<double>(i), trajectory[i].pose);
  return indexed;
}

Trajectory reference_of(const std::vector<LaserMessage>& scans) {
  Trajectory reference;
  for (std::size_t i = 0; i < scans.size(); ++i) reference.push_back(static_cast<double>(i), scans[i].odom_pose);
  return reference;
}

TEST(SpeedlessStampsRealData, OrebroIsMappedWithItsStampsAsInventedAndAsLogged) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  for (const bool index_stamps : {true, false}) {
    const std::vector<LaserMessage> scans = orebro_scans(data, index_stamps);
    ASSERT_EQ(scans.size(), 237u);
    GraphSlam graph;
    HectorSlam hector;
    for (const LaserMessage& laser : scans) {
      graph.add_scan(laser.scan, laser.odom_pose);
      hector.add_scan(laser.scan, HectorInputs{.T_odom_robot = laser.odom_pose});
    }
    graph.finish();
    // With index stamps, increment 5 (2.99 m after four steps of at most 0.6 m) stands out of the
    // steps seen so far and stays a jump; with the stamps as logged (all 0) nothing is judged by speed.
    const std::size_t jumps_allowed = index_stamps ? 1 : 0;
    EXPECT_LE(graph.odometry_stats().jumps, jumps_allowed);
    EXPECT_GT(graph.odometry_stats().speedless, 0u);
    EXPECT_LE(hector.odometry_stats().jumps, jumps_allowed);
    if (!index_stamps) {
      EXPECT_EQ(graph.odometry_stats().speedless, hector.odometry_stats().speedless);
    }
    const Trajectory reference = reference_of(scans);
    const double graph_ate = absolute_trajectory_error(by_index(graph.trajectory()), reference).rmse;
    const double hector_ate = absolute_trajectory_error(by_index(hector.trajectory()), reference).rmse;
    std::cout << "[ measured ] orebro, " << (index_stamps ? "index stamps" : "stamps as logged (0)") << ": graph "
              << graph_ate << " m, hector " << hector_ate << " m ATE; speedless " << graph.odometry_stats().speedless
              << "\n";
    EXPECT_LT(graph_ate, 1.0);
    EXPECT_LT(hector_ate, 1.0);
  }
}

}  // namespace
}  // namespace slam2d
