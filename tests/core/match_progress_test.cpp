// SPDX-License-Identifier: BSD-3-Clause
// MatchProgress: the odometry refutes a matched motion held back over four map update distances,
// and nothing shorter, nothing it did not trust, nothing that kept pace.

#include <gtest/gtest.h>

#include "slam2d/core/match_progress.hpp"

namespace slam2d {
namespace {

constexpr double kUpdate = 0.2;  // m, the method's map update distance
constexpr double kSigma = 0.04;  // m, the odometry's translation sigma over the stretch

TEST(MatchProgress, TheOdometryRefutesAMatchHeldBackOverFourUpdateDistances) {
  MatchProgress progress;
  for (int i = 0; i < 3; ++i) progress.add(SE2(0.2, 0.0, 0.0), true);
  EXPECT_FALSE(progress.refutes(SE2(), kUpdate, kSigma));  // 0.6 m: the map may yet be due
  progress.add(SE2(0.2, 0.0, 0.0), true);
  progress.add(SE2(0.2, 0.0, 0.0), true);
  EXPECT_NEAR(progress.odometry().x(), 1.0, 1e-12);
  EXPECT_TRUE(progress.refutes(SE2(), kUpdate, kSigma));                // held at the start
  EXPECT_TRUE(progress.refutes(SE2(0.85, 0.0, 0.0), kUpdate, kSigma));  // 0.15 m short: beyond 3 sigma
  EXPECT_FALSE(progress.refutes(SE2(0.9, 0.0, 0.0), kUpdate, kSigma));  // 0.10 m short: within
  EXPECT_FALSE(progress.refutes(SE2(1.1, 0.1, 0.0), kUpdate, kSigma));  // farther than the odometry: not held back
  EXPECT_FALSE(progress.refutes(SE2(0.0, 1.0, 0.0), kUpdate, kSigma));  // as far, another way: not held back
}

TEST(MatchProgress, AnIncrementTheGuardDidNotTrustLeavesTheStretchUnjudgedUntilARestart) {
  MatchProgress progress;
  progress.add(SE2(0.5, 0.0, 0.0), true);
  progress.add(SE2(0.5, 0.0, 0.0), false);  // a catch-up, a jump: not a motion to judge by
  progress.add(SE2(0.5, 0.0, 0.0), true);
  EXPECT_FALSE(progress.refutes(SE2(), kUpdate, kSigma));
  progress.restart();
  EXPECT_NEAR(progress.odometry().translation().norm(), 0.0, 1e-12);
  progress.add(SE2(0.9, 0.0, 0.0), true);
  EXPECT_TRUE(progress.refutes(SE2(), kUpdate, kSigma));
}

TEST(MatchProgress, TheStretchIsComposedInItsStartFrame) {
  MatchProgress progress;
  progress.add(SE2(0.8, 0.0, 1.5707963267948966), true);  // 0.8 m, then a quarter turn
  progress.add(SE2(0.6, 0.0, 0.0), true);                 // 0.6 m to the left of the start's heading
  EXPECT_NEAR(progress.odometry().x(), 0.8, 1e-12);
  EXPECT_NEAR(progress.odometry().y(), 0.6, 1e-12);
  EXPECT_FALSE(progress.refutes(SE2(0.8, 0.6, 1.5707963267948966), kUpdate, kSigma));  // 1 m, as matched
  EXPECT_TRUE(progress.refutes(SE2(0.5, 0.0, 0.0), kUpdate, kSigma));  // half as far: held back
}

}  // namespace
}  // namespace slam2d
