// SPDX-License-Identifier: BSD-3-Clause
// ReverseOdometryRepair on hand-made odometry: FR079 integrates reversing as forward driving.

#include <gtest/gtest.h>

#include <numbers>

#include "slam2d/core/odometry_repair.hpp"

namespace slam2d {
namespace {

OdometryReading with_tv(double tv) {
  OdometryReading reading;
  reading.tv = tv;
  return reading;
}

// A repair that trusts tv from the first step (the rules that switch it on are tested below).
ReverseOdometryRepair trusting_repair() { return ReverseOdometryRepair({.min_forward_steps = 0}); }

// Drives `steps` raw increments of `step` m along the heading from `pose`, one ODOM message with
// tv = `tv` before each; returns the last raw pose.
SE2 drive(ReverseOdometryRepair& repair, SE2 pose, int steps, double tv, double step = 0.1) {
  for (int i = 0; i < steps; ++i) {
    repair.observe(with_tv(tv));
    pose = pose * SE2(step, 0.0, 0.0);
    repair.repair(pose);
  }
  return pose;
}

TEST(ReverseOdometryRepair, MirrorsForwardStepsWhileTvIsNegative) {
  ReverseOdometryRepair repair = trusting_repair();
  const double half_pi = std::numbers::pi / 2;
  // The first scan: its raw pose is kept.
  EXPECT_TRUE(repair.repair(SE2(1.0, 2.0, half_pi)).is_approx(SE2(1.0, 2.0, half_pi)));
  // Facing +y, the raw pose advances 0.5 m along +y and turns 0.1 rad while tv < 0: the robot
  // backed up 0.5 m (to y = 1.5), the turn is kept.
  repair.observe(with_tv(-0.4));
  repair.observe(with_tv(-0.5));
  EXPECT_TRUE(repair.repair(SE2(1.0, 2.5, half_pi + 0.1)).is_approx(SE2(1.0, 1.5, half_pi + 0.1), 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 1u);
  // Forward driving with tv > 0: the step (0.2 m along the new heading) is applied as it is, from
  // the repaired pose.
  repair.observe(with_tv(0.3));
  const SE2 raw_next = SE2(1.0, 2.5, half_pi + 0.1) * SE2(0.2, 0.0, 0.0);
  const SE2 expected = SE2(1.0, 1.5, half_pi + 0.1) * SE2(0.2, 0.0, 0.0);
  EXPECT_TRUE(repair.repair(raw_next).is_approx(expected, 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 1u);
}

TEST(ReverseOdometryRepair, KeepsTheNetTravelOfAStepThatBacksUpAndDrivesOn) {
  // The odometry freezes (three scans at the same raw pose) while the robot drives forward at
  // 0.5 m/s for three ODOM messages and backs up for one; then it catches up by the travel it
  // integrated, |tv| summed: 0.4 m ahead. The robot's net travel is half of that.
  ReverseOdometryRepair repair = trusting_repair();
  const SE2 start(2.0, 1.0, -0.7);
  repair.repair(start);
  for (double tv : {0.5, 0.5, -0.5}) {
    repair.observe(with_tv(tv));
    EXPECT_TRUE(repair.repair(start).is_approx(start, 1e-12));  // frozen
  }
  repair.observe(with_tv(0.5));
  const SE2 catch_up = start * SE2(0.4, 0.02, 0.1);
  EXPECT_TRUE(repair.repair(catch_up).is_approx(start * SE2(0.2, 0.01, 0.1), 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 1u);
}

TEST(ReverseOdometryRepair, KeepsConsistentStepsAndStepsWithoutVelocity) {
  ReverseOdometryRepair repair = trusting_repair();
  repair.repair(SE2(0.0, 0.0, 0.0));
  // Already backwards while tv < 0: kept.
  repair.observe(with_tv(-0.5));
  EXPECT_TRUE(repair.repair(SE2(-0.3, 0.0, 0.0)).is_approx(SE2(-0.3, 0.0, 0.0), 1e-12));
  // No ODOM message since the last scan: kept, whatever the last tv was.
  EXPECT_TRUE(repair.repair(SE2(0.2, 0.0, 0.0)).is_approx(SE2(0.2, 0.0, 0.0), 1e-12));
  // Turning on the spot with tv < 0: no translation to mirror.
  repair.observe(with_tv(-0.02));
  EXPECT_TRUE(repair.repair(SE2(0.2, 0.0, 0.5)).is_approx(SE2(0.2, 0.0, 0.5), 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 0u);
}

TEST(ReverseOdometryRepair, StartsOnlyAfterTheLogHasDrivenForwardWithPositiveTv) {
  ReverseOdometryRepair repair;  // defaults: 20 forward steps first
  SE2 pose = SE2(0.0, 0.0, 0.3);
  repair.repair(pose);
  // Backing up with forward-moving poses before any forward driving: tv's sign is not yet known
  // to mean forward, so nothing is mirrored.
  pose = drive(repair, pose, 5, -0.5);
  EXPECT_EQ(repair.reversed_steps(), 0u);
  pose = drive(repair, pose, 20, 0.5);
  repair.observe(with_tv(-0.5));
  const SE2 repaired = repair.repair(pose * SE2(0.1, 0.0, 0.0));
  EXPECT_EQ(repair.reversed_steps(), 1u);
  EXPECT_TRUE(repaired.is_approx(pose * SE2(-0.1, 0.0, 0.0), 1e-12));
}

TEST(ReverseOdometryRepair, LeavesALogWhoseTvIsNegativeWhenDrivingForward) {
  // The other sign convention: tv < 0 while the robot drives forward, tv > 0 while it backs up
  // (and the poses follow). No step with tv > 0 ever moves forward, so tv is never trusted.
  ReverseOdometryRepair repair;
  SE2 pose(1.0, -2.0, 0.4);
  repair.repair(pose);
  for (int round = 0; round < 5; ++round) {
    pose = drive(repair, pose, 40, -0.5);
    pose = drive(repair, pose, 5, 0.3, -0.05);
  }
  repair.observe(with_tv(-0.5));
  const SE2 raw = pose * SE2(0.1, 0.0, 0.0);
  EXPECT_TRUE(repair.repair(raw).is_approx(raw, 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 0u);
}

TEST(ReverseOdometryRepair, MirrorsOnlyAMinorityOfTheForwardDriving) {
  // 20 forward steps with tv > 0, then tv < 0 on every forward step: once the mirrored steps
  // outnumber half the forward ones (11 > 20 / 2), tv's sign is no longer trusted.
  ReverseOdometryRepair repair;
  SE2 pose;
  repair.repair(pose);
  pose = drive(repair, pose, 20, 0.5);
  drive(repair, pose, 200, -0.5);
  EXPECT_EQ(repair.reversed_steps(), 11u);
}

TEST(ReverseOdometryRepair, SwitchesOffWhenThePosesRecordReversingThemselves) {
  ReverseOdometryRepair repair;
  SE2 pose;
  repair.repair(pose);
  pose = drive(repair, pose, 30, 0.5);
  // Three increments backwards with tv < 0: the poses integrate signed velocity.
  pose = drive(repair, pose, 3, -0.3, -0.05);
  EXPECT_TRUE(repair.poses_record_reversing());
  // A forward step with tv < 0 is now believed (a lagging tv), not mirrored.
  repair.observe(with_tv(-0.3));
  const SE2 raw = pose * SE2(0.05, 0.0, 0.0);
  EXPECT_TRUE(repair.repair(raw).is_approx(raw, 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 0u);
}

}  // namespace
}  // namespace slam2d
