// SPDX-License-Identifier: BSD-3-Clause
// The odometry guard (core/odometry_guard.hpp): stalls, their catch-up, jumps and gaps are
// found in hand-made odometry streams, and clean odometry is passed through untouched.

#include <gtest/gtest.h>

#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry_guard.hpp"

namespace slam2d {
namespace {

constexpr double kScanPeriod = 0.2;  // s

// Poses of a robot driving straight along x at `speed` m/s, one per scan period.
std::vector<SE2> straight_drive(int scans, double speed) {
  std::vector<SE2> poses;
  for (int k = 0; k < scans; ++k) poses.emplace_back(speed * kScanPeriod * k, 0.0, 0.0);
  return poses;
}

std::vector<OdometryCheck> check_all(OdometryGuard& guard, const std::vector<SE2>& poses) {
  std::vector<OdometryCheck> checks;
  for (std::size_t k = 0; k < poses.size(); ++k) checks.push_back(guard.check(kScanPeriod * k, poses[k]));
  return checks;
}

TEST(OdometryGuard, CleanDrivingIsTrustedAndIncrementsAreTheOdometrysOwn) {
  OdometryGuard guard;
  const std::vector<SE2> poses = straight_drive(50, 0.5);
  const std::vector<OdometryCheck> checks = check_all(guard, poses);
  EXPECT_TRUE(checks[0].first);
  for (std::size_t k = 1; k < checks.size(); ++k) {
    EXPECT_TRUE(checks[k].trusted()) << k;
    EXPECT_EQ(checks[k].increment.vector(), poses[k - 1].between(poses[k]).vector());
  }
  EXPECT_EQ(guard.stats().untrusted(), 0u);
  EXPECT_EQ(guard.stats().checks, 49u);
}

// The held-out log's fault: five scans with the same odometry pose while the robot drives on,
// then the odometry catches up in one step.
TEST(OdometryGuard, FrozenPoseAfterMotionIsAStallAndTheCatchUpIsNotTrusted) {
  std::vector<SE2> poses = straight_drive(30, 0.5);
  for (int k = 11; k <= 15; ++k) poses[k] = poses[10];  // frozen for five scans; scan 16 catches up
  OdometryGuard guard;
  const std::vector<OdometryCheck> checks = check_all(guard, poses);
  for (int k = 1; k <= 11; ++k) EXPECT_TRUE(checks[k].trusted()) << k;  // frozen 0.2 s: not yet a stall
  for (int k = 12; k <= 15; ++k) EXPECT_EQ(checks[k].fault, OdometryFault::kStall) << k;
  EXPECT_EQ(checks[16].fault, OdometryFault::kCatchUp);
  EXPECT_NEAR(checks[16].increment.x(), 0.6, 1e-12);  // six scans of motion in one increment
  for (int k = 17; k < 30; ++k) EXPECT_TRUE(checks[k].trusted()) << k;
  EXPECT_EQ(guard.stats().stalls, 1u);
  EXPECT_EQ(guard.stats().stalled_scans, 4u);
  EXPECT_EQ(guard.stats().catch_ups, 1u);
}

// A stall is waited out (no map written at its scans) while its catch-up can still put the pose
// right: up to max_held_stall seconds after the pose last changed; after that, and at the
// catch-up, the maps follow the scan matching again.
TEST(OdometryGuard, AStallHoldsTheMapUpToMaxHeldStall) {
  std::vector<SE2> poses = straight_drive(60, 0.5);
  for (int k = 11; k <= 40; ++k) poses[k] = poses[10];  // frozen 6 s after scan 10; scan 41 catches up
  OdometryGuard guard(OdometryGuardConfig{.max_held_stall = 3.0});
  const std::vector<OdometryCheck> checks = check_all(guard, poses);
  for (int k = 1; k <= 11; ++k) EXPECT_FALSE(checks[k].hold_map) << k;  // trusted
  for (int k = 12; k <= 40; ++k) {
    ASSERT_EQ(checks[k].fault, OdometryFault::kStall) << k;
    EXPECT_EQ(checks[k].hold_map, kScanPeriod * (k - 10) <= 3.0 + 1e-9) << k;
  }
  EXPECT_TRUE(checks[25].hold_map);
  EXPECT_FALSE(checks[26].hold_map);
  EXPECT_EQ(checks[41].fault, OdometryFault::kCatchUp);
  EXPECT_FALSE(checks[41].hold_map);
  // 0 holds nothing; a robot at rest is never held.
  OdometryGuard never(OdometryGuardConfig{.max_held_stall = 0.0});
  for (const OdometryCheck& check : check_all(never, poses)) EXPECT_FALSE(check.hold_map);
  std::vector<SE2> resting{SE2(0, 0, 0), SE2(0.005, 0, 0)};
  for (int k = 0; k < 20; ++k) resting.push_back(resting.back());
  OdometryGuard at_rest;
  for (const OdometryCheck& check : check_all(at_rest, resting)) EXPECT_FALSE(check.hold_map);
}

// An odometry that restarts from its origin while the robot stands: the first increment after the
// rest is beyond what the robot could have driven since the pose last changed, so it is a jump,
// not a catch-up applied from where the odometry last moved.
TEST(OdometryGuard, ARestartAfterARestIsAJumpNotACatchUp) {
  std::vector<SE2> poses{SE2(20.0, 5.0, 1.0), SE2(20.05, 5.0, 1.0)};
  for (int k = 0; k < 10; ++k) poses.push_back(poses.back());  // at rest for 2 s
  OdometryGuard guard;
  check_all(guard, poses);
  EXPECT_EQ(guard.check(kScanPeriod * 12, SE2()).fault, OdometryFault::kJump);  // 20.6 m in 2.2 s
  EXPECT_EQ(guard.stats().catch_ups, 0u);
  // The same rest ended by 0.3 m in one step (a freeze that began at rest) is a catch-up.
  OdometryGuard rested;
  check_all(rested, poses);
  EXPECT_EQ(rested.check(kScanPeriod * 12, SE2(20.35, 5.0, 1.0)).fault, OdometryFault::kCatchUp);
}

// A restart onto the origin within the bounds: after a 2 s gap the step from 1.1 m back to
// (0, 0, 0) is less than the robot could have driven, yet it is a jump; the increments after it
// are trusted again. A step that only passes near the origin is motion.
TEST(OdometryGuard, AStepOntoTheOriginIsARestartWhateverItsSize) {
  OdometryGuard guard;
  guard.check(0.0, SE2(1.0, 0.0, 0.2));
  guard.check(0.1, SE2(1.05, 0.0, 0.2));
  const OdometryCheck restart = guard.check(2.1, SE2());  // 1.05 m and 0.2 rad in 2 s: within the bounds
  EXPECT_EQ(restart.fault, OdometryFault::kJump);
  EXPECT_TRUE(guard.check(2.2, SE2(0.05, 0.0, 0.0)).trusted());
  EXPECT_EQ(guard.stats().jumps, 1u);

  OdometryGuard passing;
  passing.check(0.0, SE2(-0.05, 0.0, 0.0));
  EXPECT_TRUE(passing.check(0.1, SE2(0.0, 0.0, 0.01)).trusted());  // 10 mrad off the origin's heading
  EXPECT_TRUE(passing.check(0.2, SE2(0.05, 0.0, 0.01)).trusted());
  // A log that starts at the origin and stands there is at rest, not restarting.
  OdometryGuard resting;
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(resting.check(0.1 * k, SE2()).trusted());
  EXPECT_EQ(resting.stats().jumps, 0u);
}

// Intel: a scan 1.2 ms after the last one carries its odometry pose; the odometry is slower
// than the scanner there, not stalled.
TEST(OdometryGuard, APoseRepeatedWithinTheStallDurationIsNotAStall) {
  OdometryGuard guard;
  guard.check(0.0, SE2());
  guard.check(0.1, SE2(0.05, 0.0, 0.0));
  EXPECT_TRUE(guard.check(0.1012, SE2(0.05, 0.0, 0.0)).trusted());
  EXPECT_TRUE(guard.check(0.2, SE2(0.1, 0.0, 0.0)).trusted());
  EXPECT_EQ(guard.stats().stalls, 0u);
}

TEST(OdometryGuard, ARobotComingToRestIsNotAStall) {
  // Slowing down through small increments, then standing: "no motion" is true.
  std::vector<SE2> poses{SE2(0, 0, 0), SE2(0.05, 0, 0), SE2(0.08, 0, 0), SE2(0.09, 0, 0), SE2(0.095, 0, 0)};
  for (int k = 0; k < 20; ++k) poses.push_back(poses.back());
  poses.emplace_back(0.1, 0, 0);
  OdometryGuard guard;
  const std::vector<OdometryCheck> checks = check_all(guard, poses);
  for (std::size_t k = 0; k + 1 < checks.size(); ++k) EXPECT_TRUE(checks[k].trusted()) << k;
  EXPECT_EQ(guard.stats().stalls, 0u);
  // Driving off again by 5 mm in 0.1 s is what a robot starting from rest does: trusted.
  EXPECT_TRUE(checks.back().trusted());
  EXPECT_TRUE(checks.back().moved);
  EXPECT_FALSE(checks[10].moved);
  EXPECT_TRUE(checks[4].moved);
}

TEST(OdometryGuard, AFirstIncrementAfterARestBeyondAStartFromRestIsACatchUp) {
  // A freeze that begins at rest looks like the rest; the robot turns meanwhile, and the first
  // increment after it carries the turn: more than a robot starting from rest could turn in one
  // step, so it is a catch-up, applied from the scan where the pose last moved.
  for (const double dt : {0.1, 0.25, 2.0}) {  // beyond max_startup_time the bound stops growing
    std::vector<SE2> poses{SE2(0, 0, 0), SE2(0.05, 0, 0), SE2(0.06, 0, 0)};
    for (int k = 0; k < 10; ++k) poses.push_back(poses.back());
    OdometryGuard guard;
    const std::vector<OdometryCheck> checks = check_all(guard, poses);
    const OdometryCheck check = guard.check(1.2 + dt, SE2(0.06, 0.0, 0.3));  // 0.3 rad in dt
    for (const OdometryCheck& c : checks) EXPECT_TRUE(c.trusted());
    EXPECT_EQ(check.fault, OdometryFault::kCatchUp) << dt;
    EXPECT_TRUE(check.moved);
  }
  // The same first increment after a short pause (under stall_duration) is just motion.
  OdometryGuard guard;
  guard.check(0.0, SE2(0.05, 0, 0));
  guard.check(0.1, SE2(0.06, 0, 0));
  EXPECT_EQ(guard.check(0.2, SE2(0.06, 0, 0.3)).fault, OdometryFault::kNone);
}

TEST(OdometryGuard, AnIncrementBeyondTheRobotsSpeedIsAJump) {
  std::vector<SE2> poses = straight_drive(20, 0.5);
  for (int k = 10; k < 20; ++k) poses[k] = SE2(0.86, 0.0, 0.85) * poses[k];  // 0.86 m and 0.85 rad in one step
  OdometryGuard guard;
  const std::vector<OdometryCheck> checks = check_all(guard, poses);
  EXPECT_EQ(checks[10].fault, OdometryFault::kJump);
  for (int k = 11; k < 20; ++k) EXPECT_TRUE(checks[k].trusted()) << k;
  EXPECT_EQ(guard.stats().jumps, 1u);
  // The same step over a long enough time is plausible (a gap, not a jump).
  OdometryGuard slow;
  slow.check(0.0, SE2());
  const OdometryCheck over_gap = slow.check(3.0, SE2(0.86, 0.0, 0.85));
  EXPECT_TRUE(over_gap.trusted());
  EXPECT_TRUE(over_gap.gap);
  EXPECT_EQ(slow.stats().gaps, 1u);
}

// ACES at 613 s: after a 3 s gap the scan's odometry lags, and the next increment, 0.16 s later,
// carries 1.06 rad of the turn made during the gap. It is bounded over the gap's time too.
TEST(OdometryGuard, TheIncrementAfterAGapMayCarryTheGapsMotion) {
  OdometryGuard guard;
  guard.check(0.0, SE2());
  EXPECT_TRUE(guard.check(3.0, SE2(0.0, 0.0, 0.39)).gap);
  const OdometryCheck lagged = guard.check(3.16, SE2(0.38, 0.0, 1.45));
  EXPECT_TRUE(lagged.trusted());
  // Without the gap before it, the same increment is a jump.
  OdometryGuard no_gap;
  no_gap.check(0.0, SE2());
  no_gap.check(0.2, SE2(0.0, 0.0, 0.39));
  EXPECT_EQ(no_gap.check(0.36, SE2(0.38, 0.0, 1.45)).fault, OdometryFault::kJump);
}

// ACES played backwards: the odometry lagged at the scan after its 3 s pause, so backwards the
// increment before the pause turns 1.06 rad in 0.16 s (a jump) and the one across it 0.39 rad,
// where the robot turned 1.45. The increment after the jump is the motion since the reading before
// it, a catch-up that starts there (the jumped reading is no reference: moved is false).
TEST(OdometryGuard, AnOdometryBackAfterAJumpIsACatchUpFromTheReadingBeforeIt) {
  OdometryGuard guard;
  for (int k = 0; k <= 10; ++k) guard.check(0.2 * k, SE2(0.05 * k, 0.0, 0.0));
  const SE2 before(0.5, 0.0, 0.0);
  const SE2 stale = before * SE2(0.38, 0.0, 1.06);
  const SE2 after = before * SE2(0.1, 0.05, 1.45);
  const OdometryCheck jumped = guard.check(2.16, stale);
  EXPECT_EQ(jumped.fault, OdometryFault::kJump);
  EXPECT_FALSE(jumped.moved);
  const OdometryCheck back = guard.check(5.19, after);
  EXPECT_EQ(back.fault, OdometryFault::kCatchUp);
  EXPECT_TRUE(back.moved);
  EXPECT_NEAR((back.increment.vector() - before.between(after).vector()).norm(), 0.0, 1e-12);
  EXPECT_EQ(guard.stats().returns, 1u);
  EXPECT_EQ(guard.stats().jumps, 1u);
  // Trusted again from there on.
  EXPECT_TRUE(guard.check(5.39, after * SE2(0.05, 0.0, 0.0)).trusted());

  // A spike: one reading 0.9 m off in a stream at 10 Hz, the next back in line.
  OdometryGuard spiked;
  std::vector<SE2> poses = straight_drive(20, 0.5);
  poses[10] = SE2(0.0, 0.9, 0.0) * poses[10];
  const std::vector<OdometryCheck> checks = check_all(spiked, poses);
  EXPECT_EQ(checks[10].fault, OdometryFault::kJump);
  EXPECT_EQ(checks[11].fault, OdometryFault::kCatchUp);
  EXPECT_NEAR((checks[11].increment.vector() - poses[9].between(poses[11]).vector()).norm(), 0.0, 1e-12);
  for (int k = 12; k < 20; ++k) EXPECT_TRUE(checks[k].trusted()) << k;

  // An odometry that jumped for good is not "back": its next increments are trusted as they are,
  // and the reference moves on with them.
  OdometryGuard jumped_for_good;
  std::vector<SE2> shifted = straight_drive(20, 0.5);
  for (int k = 10; k < 20; ++k) shifted[k] = SE2(0.86, 0.0, 0.85) * shifted[k];
  const std::vector<OdometryCheck> kept = check_all(jumped_for_good, shifted);
  EXPECT_EQ(kept[10].fault, OdometryFault::kJump);
  for (int k = 11; k < 20; ++k) {
    EXPECT_TRUE(kept[k].trusted()) << k;
    EXPECT_TRUE(kept[k].moved) << k;
  }
  EXPECT_EQ(jumped_for_good.stats().returns, 0u);

  // A restart is a new frame for good: no return to the reading before it, whatever the time.
  OdometryGuard restarted;
  restarted.check(0.0, SE2(1.0, 1.0, 1.0));
  EXPECT_EQ(restarted.check(0.2, SE2()).fault, OdometryFault::kJump);
  EXPECT_TRUE(restarted.check(3.0, SE2(1.0, 1.0, 1.0)).trusted());
  EXPECT_EQ(restarted.stats().returns, 0u);
}

// Intel with its odometry 0.6 s ahead, compensated: across a 2.4 s pause in the stamps (really one
// scan's time: the robot turned 0.1 rad) the odometry, interpolated along the stamps, turns 1.3 rad.
// An increment that moved over a pause in the log's rhythm (shorter than a gap too) stays trusted
// but is to be confirmed by the scans; one that did not move, or one over the log's own rhythm (a
// scan every 1.5 s, as in the SLAM-corrected logs), is not.
TEST(OdometryGuard, AnIncrementThatMovedOverAPauseIsToBeConfirmed) {
  const auto drive = [](OdometryGuard& guard, double period, int scans) {
    for (int k = 0; k < scans; ++k) EXPECT_FALSE(guard.check(period * k, SE2(0.1 * k, 0.0, 0.02 * k)).confirm) << k;
    return period * (scans - 1);
  };
  OdometryGuard guard;
  double stamp = drive(guard, 0.2, 10);
  const OdometryCheck turned = guard.check(stamp += 2.4, SE2(1.0, 0.0, 1.5));
  EXPECT_TRUE(turned.gap);
  EXPECT_TRUE(turned.trusted());
  EXPECT_TRUE(turned.confirm);
  const OdometryCheck rested = guard.check(stamp += 2.4, SE2(1.0, 0.0, 1.5));  // a pause, no motion
  EXPECT_TRUE(rested.gap);
  EXPECT_FALSE(rested.confirm);
  EXPECT_EQ(guard.stats().pause_confirmations, 1u);

  OdometryGuard fast;  // a scan every 0.1 s, then one after 0.8 s: no gap, but a pause
  stamp = drive(fast, 0.1, 20);
  const OdometryCheck short_pause = fast.check(stamp + 0.8, SE2(2.5, 0.0, 1.0));
  EXPECT_FALSE(short_pause.gap);
  EXPECT_TRUE(short_pause.confirm);
  EXPECT_FALSE(fast.check(stamp + 0.8 + 0.3, SE2(2.6, 0.0, 1.02)).confirm) << "three steps of the rhythm";

  OdometryGuard slow;
  stamp = drive(slow, 1.5, 10);
  const OdometryCheck step = slow.check(stamp + 1.6, SE2(1.2, 0.0, 0.5));
  EXPECT_TRUE(step.gap);
  EXPECT_FALSE(step.confirm);

  OdometryGuardConfig off;
  off.confirm_pause = 0.0;
  OdometryGuard unconfirmed(off);
  stamp = drive(unconfirmed, 0.2, 10);
  EXPECT_FALSE(unconfirmed.check(stamp + 2.4, SE2(1.0, 0.0, 1.5)).confirm);
}

// Intel's burst after a pause: scans 1 ms apart, taken during the pause, over which the odometry
// (interpolated along the stamps) stands. A trusted increment that stood over a step shorter than
// the median over confirm_burst is to be confirmed by the scans; one that moved, one over the log's
// rhythm, one before the rhythm is known or with confirm_burst 0 is not.
TEST(OdometryGuard, AnIncrementThatStoodWithinABurstIsToBeConfirmed) {
  OdometryGuard guard({.confirm_burst = 5.0});
  EXPECT_FALSE(guard.check(0.0, SE2()).burst);
  EXPECT_FALSE(guard.check(0.001, SE2()).burst) << "no rhythm known yet";
  double stamp = 0.001;
  for (int k = 1; k <= 10; ++k) EXPECT_FALSE(guard.check(stamp += 0.1, SE2(0.1 * k, 0.0, 0.0)).burst) << k;
  const OdometryCheck stood = guard.check(stamp += 0.001, SE2(1.0, 0.0, 0.0));
  EXPECT_TRUE(stood.trusted());
  EXPECT_TRUE(stood.burst);
  EXPECT_FALSE(stood.confirm);
  EXPECT_FALSE(guard.check(stamp += 0.001, SE2(1.1, 0.0, 0.0)).burst) << "it moved";
  EXPECT_FALSE(guard.check(stamp += 0.03, SE2(1.1, 0.0, 0.0)).burst) << "a third of the rhythm";
  EXPECT_TRUE(guard.check(stamp += 0.001, SE2(1.1, 0.0, 0.0)).burst);
  EXPECT_EQ(guard.stats().burst_checks, 2u);

  OdometryGuard unconfirmed;  // off by default
  stamp = 0.0;
  for (int k = 0; k <= 10; ++k) unconfirmed.check(stamp += 0.1, SE2(0.1 * k, 0.0, 0.0));
  EXPECT_FALSE(unconfirmed.check(stamp += 0.001, SE2(1.0, 0.0, 0.0)).burst);
}

TEST(OdometryGuard, ShortOrBackwardTimeStepsDoNotShrinkTheBound) {
  OdometryGuard guard;
  guard.check(10.0, SE2());
  // 0.25 m with a stamp that stepped back: within max_speed * min_time_step + slack.
  EXPECT_TRUE(guard.check(9.99, SE2(0.25, 0.0, 0.0)).trusted());
}

// Stamps that carry no speed: the raw SLAM-corrected Orebro log stamps every scan 0, and its
// scans lie about a metre apart; invented at one second a scan, its ordinary steps reach 3.3 m.
TEST(OdometryGuard, StampsThatDoNotAdvanceCarryNoSpeed) {
  OdometryGuard guard;
  for (int k = 0; k < 20; ++k) {
    const OdometryCheck check = guard.check(0.0, SE2(1.0 * k, 0.1 * (k % 3), 0.05 * k));
    EXPECT_TRUE(check.trusted()) << k;
  }
  EXPECT_EQ(guard.stats().jumps, 0u);
  EXPECT_EQ(guard.stats().speedless, 19u);
  // A restart onto the origin is still a jump: it needs no speed.
  EXPECT_EQ(guard.check(0.0, SE2()).fault, OdometryFault::kJump);
}

TEST(OdometryGuard, StepsWithinTheLogsOwnAreNoJumpsButAStepBeyondThemIs) {
  OdometryGuard guard;
  // One scan a second, steps of 1 to 3.3 m (Orebro's): beyond 2 m/s, within the log's own steps.
  const double steps[] = {1.0, 1.1, 0.9, 2.0, 1.05, 3.0, 1.0, 1.2, 3.3, 0.95, 1.0, 2.4};
  double x = 0.0;
  guard.check(0.0, SE2());
  for (int k = 0; k < 12; ++k) {
    x += steps[k];
    EXPECT_TRUE(guard.check(1.0 + k, SE2(x, 0.0, 0.0)).trusted()) << k;
  }
  EXPECT_EQ(guard.stats().speedless, 3u);  // the 3.0, 3.3 and 2.4 m steps
  // 15 m in one second is a jump: beyond the speed bound and four times the log's steps.
  EXPECT_EQ(guard.check(13.0, SE2(x + 15.0, 0.0, 0.0)).fault, OdometryFault::kJump);
  // Off (step_factor 0), the speed bounds alone judge, as before.
  OdometryGuard speed_only(OdometryGuardConfig{.step_factor = 0.0});
  speed_only.check(0.0, SE2());
  speed_only.check(1.0, SE2(1.0, 0.0, 0.0));
  EXPECT_EQ(speed_only.check(2.0, SE2(4.0, 0.0, 0.0)).fault, OdometryFault::kJump);
}

TEST(OdometryGuard, DisabledTrustsEverything) {
  std::vector<SE2> poses = straight_drive(20, 0.5);
  for (int k = 6; k <= 9; ++k) poses[k] = poses[5];
  OdometryGuard guard(OdometryGuardConfig{.enabled = false});
  for (const OdometryCheck& check : check_all(guard, poses)) EXPECT_TRUE(check.trusted());
}

TEST(OdometryGuard, RejectsInvalidConfigs) {
  EXPECT_THROW(OdometryGuard(OdometryGuardConfig{.max_speed = 0.0}), Error);
  EXPECT_THROW(OdometryGuard(OdometryGuardConfig{.min_time_step = -1.0}), Error);
  EXPECT_THROW(OdometryGuard(OdometryGuardConfig{.jump_rotation_slack = -0.1}), Error);
  EXPECT_THROW(OdometryGuard(OdometryGuardConfig{.step_history = 2, .min_step_history = 3}), Error);
  EXPECT_THROW(OdometryGuard(OdometryGuardConfig{.max_held_stall = -1.0}), Error);
  EXPECT_THROW(OdometryGuard(OdometryGuardConfig{.restart_translation = -1e-3}), Error);
}

}  // namespace
}  // namespace slam2d
