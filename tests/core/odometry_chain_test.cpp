// SPDX-License-Identifier: BSD-3-Clause
// The laser chain and the odometry moved in time along it (core/odometry_chain.hpp): hand-computed
// interpolations, a stamp written late, ends held, and a shift undone by the opposite shift.

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
  const OdometryChain chain = laser_odometry_chain(messages);
  ASSERT_EQ(chain.size(), 4u);
  EXPECT_EQ(chain[0].message, 1u);
  EXPECT_EQ(chain[2].message, 5u);
  EXPECT_EQ(chain[3].message, 6u);
  EXPECT_DOUBLE_EQ(chain[3].pose.x(), 0.5);
}

TEST(OdometryChain, InterpolatesBetweenTheEntriesThatBracketTheStamp) {
  const OdometryChain chain = laser_odometry_chain(steady_log(6));
  // 0.5 s: halfway between the entries at 0.4 and 0.6 s; 0.25 s, a quarter from 0.2 to 0.4 s.
  EXPECT_TRUE(test::poses_near(chain.at(0, 0.5), SE2(0.5, 0.0, 0.05), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(chain.at(5, 0.25), SE2(0.25, 0.0, 0.025), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(chain.at(2, 0.4), SE2(0.4, 0.0, 0.04), 1e-12, 1e-12));
}

TEST(OdometryChain, HoldsTheEndPosesBeyondTheChain) {
  const OdometryChain chain = laser_odometry_chain(steady_log(4));
  EXPECT_TRUE(test::poses_near(chain.at(1, -3.0), SE2(0.0, 0.0, 0.0), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(chain.at(1, 9.0), SE2(0.6, 0.0, 0.06), 1e-12, 1e-12));
}

TEST(OdometryChain, AStampWrittenLateKeepsItsPlaceOnThePath) {
  // Scans every second at x = t, the fourth stamped 3.5 s where it was taken at 3 s (Intel writes
  // a line up to 0.9 s late, the next ones on time): the chain's clock lowers it to the next
  // stamp, 4 s, so its pose stays between its neighbours' and the path does not turn back.
  std::vector<SensorMessage> messages;
  for (double t : {0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0}) messages.emplace_back(scan_at(t == 3.0 ? 4.5 : t, SE2(t, 0.0, 0.0)));
  const OdometryChain chain = laser_odometry_chain(messages);
  EXPECT_DOUBLE_EQ(chain[3].stamp, 4.0);
  EXPECT_DOUBLE_EQ(chain[3].pose.x(), 3.0);
  EXPECT_DOUBLE_EQ(chain[4].stamp, 4.0);
  EXPECT_NEAR(chain.at(1, 1.5).x(), 1.5, 1e-12);                 // away from it, exact
  EXPECT_NEAR(chain.at(1, 3.0).x(), 2.5, 1e-12);                 // between 2 s and the late one at "4 s"
  EXPECT_DOUBLE_EQ(chain.at(3, 4.0).x(), 3.0);                   // each sample at its own stamp: its pose,
  EXPECT_DOUBLE_EQ(chain.at(4, 4.0).x(), 4.0);                   // whatever samples share the stamp
  EXPECT_NEAR(chain.at(3, 4.5).x(), 4.5, 1e-12);
  double previous = -1.0;
  for (std::size_t k = 0; k < chain.size(); ++k) {
    const double x = chain.shifted(k, 0.7).x();
    EXPECT_GE(x, previous) << k;
    previous = x;
  }
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

TEST(OdometryChain, ShiftingALogWhoseStampsNeverAdvanceHoldsItsEnds) {
  // All stamps 0 (Örebro's): every later time is beyond the chain's end, every earlier one before
  // its start. A binary search per pose: no walk along the chain's 10^4 samples.
  std::vector<SensorMessage> messages;
  for (int i = 0; i < 10000; ++i) messages.emplace_back(scan_at(0.0, SE2(i, 0.0, 0.0)));
  std::vector<SensorMessage> back = messages;
  EXPECT_EQ(shift_scan_odometry(messages, 0.5), 9999u);
  EXPECT_DOUBLE_EQ(std::get<LaserMessage>(messages[0]).odom_pose.x(), 9999.0);
  EXPECT_EQ(shift_scan_odometry(back, -0.5), 9999u);
  EXPECT_DOUBLE_EQ(std::get<LaserMessage>(back[9999]).odom_pose.x(), 0.0);
  EXPECT_EQ(shift_scan_odometry(messages, 0.0), 0u);
}

}  // namespace
}  // namespace slam2d
