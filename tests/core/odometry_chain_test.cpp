// SPDX-License-Identifier: BSD-3-Clause
// The laser chain and the odometry moved in time along it (core/odometry_chain.hpp): hand-computed
// interpolations, stamps that step back, ends held, and a shift undone by the opposite shift.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "slam2d/core/odometry_chain.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

LaserMessage scan_at(double stamp, const SE2& odometry) {
  LaserMessage laser;
  laser.type = "FLASER";
  laser.scan.stamp = stamp;
  laser.odom_pose = odometry;
  laser.laser_pose = odometry;
  return laser;
}

// A robot driving 1 m/s along x and turning 0.1 rad/s, one scan every 0.2 s, an ODOM between.
std::vector<SensorMessage> steady_log(std::size_t scans) {
  std::vector<SensorMessage> messages;
  for (std::size_t i = 0; i < scans; ++i) {
    const double t = 0.2 * static_cast<double>(i);
    messages.emplace_back(OdometryMessage{.reading = {.stamp = t, .pose = SE2(t, 0.0, 0.1 * t)}});
    messages.emplace_back(scan_at(t, SE2(t, 0.0, 0.1 * t)));
  }
  return messages;
}

TEST(OdometryChain, HoldsTheLaserLinesAndTruePosesInFileOrderButNotOdom) {
  std::vector<SensorMessage> messages = steady_log(3);
  messages.emplace_back(TruePoseMessage{.stamp = 0.5, .true_pose = SE2(), .odom_pose = SE2(0.5, 0.0, 0.05)});
  const std::vector<ChainPose> chain = laser_odometry_chain(messages);
  ASSERT_EQ(chain.size(), 4u);
  EXPECT_EQ(chain[0].message, 1u);
  EXPECT_EQ(chain[2].message, 5u);
  EXPECT_EQ(chain[3].message, 6u);
  EXPECT_DOUBLE_EQ(chain[3].pose.x(), 0.5);
}

TEST(OdometryChain, InterpolatesBetweenTheEntriesThatBracketTheStamp) {
  const std::vector<ChainPose> chain = laser_odometry_chain(steady_log(6));
  // 0.5 s: halfway between the entries at 0.4 and 0.6 s; 0.25 s, a quarter from 0.2 to 0.4 s.
  EXPECT_TRUE(test::poses_near(chain_pose_at(chain, 0, 0.5), SE2(0.5, 0.0, 0.05), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(chain_pose_at(chain, 5, 0.25), SE2(0.25, 0.0, 0.025), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(chain_pose_at(chain, 2, 0.4), SE2(0.4, 0.0, 0.04), 1e-12, 1e-12));
}

TEST(OdometryChain, HoldsTheEndPosesBeyondTheChain) {
  const std::vector<ChainPose> chain = laser_odometry_chain(steady_log(4));
  EXPECT_TRUE(test::poses_near(chain_pose_at(chain, 1, -3.0), SE2(0.0, 0.0, 0.0), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(chain_pose_at(chain, 1, 9.0), SE2(0.6, 0.0, 0.06), 1e-12, 1e-12));
}

TEST(OdometryChain, WalksInFileOrderSoThatAStampSteppingBackElsewhereDoesNotMisleadIt) {
  // Stamps 0, 1, 2, 0.5 (out of order, far from the query), 3, 4: the query from entry 1 at
  // 1.5 s must use entries 1 and 2, not the late entry stamped 0.5.
  std::vector<SensorMessage> messages;
  for (double t : {0.0, 1.0, 2.0}) messages.emplace_back(scan_at(t, SE2(t, 0.0, 0.0)));
  messages.emplace_back(scan_at(0.5, SE2(10.0, 0.0, 0.0)));
  for (double t : {3.0, 4.0}) messages.emplace_back(scan_at(t, SE2(t, 0.0, 0.0)));
  const std::vector<ChainPose> chain = laser_odometry_chain(messages);
  EXPECT_NEAR(chain_pose_at(chain, 1, 1.5).x(), 1.5, 1e-12);
  // From entry 4 (3 s) back to 2.5 s: the first neighbours in file order whose stamps bracket it
  // are the entry stamped 0.5 s and the one at 3 s.
  EXPECT_NEAR(chain_pose_at(chain, 4, 2.5).x(), 10.0 + (3.0 - 10.0) * (2.0 / 2.5), 1e-12);
}

TEST(OdometryChain, AShiftGivesEachScanTheOdometryOfLaterAndTheOppositeShiftUndoesIt) {
  std::vector<SensorMessage> messages = steady_log(30);
  const std::vector<SensorMessage> original = messages;
  EXPECT_EQ(shift_scan_odometry(messages, 0.3), 29u);  // the last scan holds the chain's end
  const auto& shifted = std::get<LaserMessage>(messages[11]);  // scan 5, at 1 s
  EXPECT_TRUE(test::poses_near(shifted.odom_pose, SE2(1.3, 0.0, 0.13), 1e-12, 1e-12));
  EXPECT_TRUE(shifted.laser_pose == shifted.odom_pose);  // the raw log's estimated pose follows
  EXPECT_DOUBLE_EQ(std::get<OdometryMessage>(messages[10]).reading.pose.x(), 1.0);  // ODOM kept
  shift_scan_odometry(messages, -0.3);
  for (std::size_t i = 4; i + 6 < messages.size(); ++i) {
    if (const auto* laser = std::get_if<LaserMessage>(&messages[i])) {
      EXPECT_TRUE(test::poses_near(laser->odom_pose, std::get<LaserMessage>(original[i]).odom_pose, 1e-9, 1e-9)) << i;
    }
  }
}

TEST(OdometryChain, ShiftingALogWhoseStampsNeverAdvanceEnds) {
  std::vector<SensorMessage> messages;
  for (int i = 0; i < 10000; ++i) messages.emplace_back(scan_at(0.0, SE2(i, 0.0, 0.0)));
  shift_scan_odometry(messages, 0.5);  // all stamps 0: every walk stops after kMaxChainWalk entries
  EXPECT_EQ(messages.size(), 10000u);
  EXPECT_DOUBLE_EQ(std::get<LaserMessage>(messages[0]).odom_pose.x(), static_cast<double>(kMaxChainWalk + 1));
  EXPECT_EQ(shift_scan_odometry(messages, 0.0), 0u);
}

}  // namespace
}  // namespace slam2d
