// SPDX-License-Identifier: BSD-3-Clause
// Tests of the relative pose error (Sturm et al. 2012) with time and distance windows.

#include "slam2d/eval/rpe.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

// Poses at stamps 0, 1, 2, ... built by composing `step` from `start`.
Trajectory steps(const SE2& start, const SE2& step, int count) {
  Trajectory trajectory;
  SE2 pose = start;
  for (int k = 0; k < count; ++k) {
    trajectory.push_back(k, pose);
    pose = pose * step;
  }
  return trajectory;
}

TEST(Rpe, TimeWindowWithAConstantScaleError) {
  // Reference 1 m/s, estimate 1.1 m/s: over 2 s the error is 0.2 m; pairs (0,2) ... (8,10).
  const Trajectory reference = steps(SE2(0.0, 0.0, 0.5), SE2(1.0, 0.0, 0.0), 11);
  const Trajectory estimate = steps(SE2(4.0, 3.0, -1.0), SE2(1.1, 0.0, 0.0), 11);
  const RpeResult r = relative_pose_error(estimate, reference, {.window = RpeWindow::kTime, .delta = 2.0});
  EXPECT_EQ(r.matched, 11u);
  EXPECT_EQ(r.pairs, 9u);
  EXPECT_NEAR(r.translation.rmse, 0.2, 1e-12);
  EXPECT_NEAR(r.translation.mean, 0.2, 1e-12);
  EXPECT_NEAR(r.translation.max, 0.2, 1e-12);
  EXPECT_NEAR(r.rotation_deg.max, 0.0, 1e-12);
}

TEST(Rpe, TimeWindowWithAConstantTurnError) {
  // The estimate turns by 0.1 rad per step where the reference goes straight. Over two steps the
  // estimate's motion is (1 + cos 0.1, sin 0.1, 0.2) against (2, 0, 0): the error is
  // (cos 0.1 - 1, sin 0.1, 0.2), of length sqrt(2 - 2 cos 0.1) = 2 sin 0.05.
  const Trajectory reference = steps(SE2(), SE2(1.0, 0.0, 0.0), 6);
  const Trajectory estimate = steps(SE2(), SE2(1.0, 0.0, 0.1), 6);
  const RpeResult one = relative_pose_error(estimate, reference, {.window = RpeWindow::kTime, .delta = 1.0});
  EXPECT_EQ(one.pairs, 5u);
  EXPECT_NEAR(one.translation.max, 0.0, 1e-12);
  EXPECT_NEAR(one.rotation_deg.rmse, rad_to_deg(0.1), 1e-10);
  EXPECT_NEAR(one.rotation_deg.mean, rad_to_deg(0.1), 1e-10);
  const RpeResult two = relative_pose_error(estimate, reference, {.window = RpeWindow::kTime, .delta = 1.5});
  EXPECT_EQ(two.pairs, 4u);  // the first pose at least 1.5 s later is 2 s later
  EXPECT_NEAR(two.translation.mean, 2.0 * std::sin(0.05), 1e-12);
  EXPECT_NEAR(two.rotation_deg.max, rad_to_deg(0.2), 1e-10);
}

// Reference steps of 1, 1, 2, 0.5, 0.5, 3 m along x (path positions 0 1 2 4 4.5 5 8) at stamps
// 0..6; the estimate's steps are 1.5 times longer.
struct StretchCase {
  Trajectory reference;
  Trajectory estimate;
};

StretchCase stretch_case() {
  const std::vector<double> lengths{1.0, 1.0, 2.0, 0.5, 0.5, 3.0};
  StretchCase c;
  double x = 0.0;
  c.reference.push_back(0.0, SE2(0.0, 0.0, 0.0));
  c.estimate.push_back(0.0, SE2(0.0, 0.0, 0.0));
  for (std::size_t k = 0; k < lengths.size(); ++k) {
    x += lengths[k];
    c.reference.push_back(static_cast<double>(k + 1), SE2(x, 0.0, 0.0));
    c.estimate.push_back(static_cast<double>(k + 1), SE2(1.5 * x, 0.0, 0.0));
  }
  return c;
}

TEST(Rpe, DistanceWindowPicksTheFirstPoseAtLeastDeltaFurther) {
  // delta = 2 m: pairs (0,2) (1,3) (2,3) (3,6) (4,6) (5,6) span 2 3 2 4 3.5 3 m, and the errors are
  // half of that: 1 1.5 1 2 1.75 1.5 m.
  const StretchCase c = stretch_case();
  const RpeResult r = relative_pose_error(c.estimate, c.reference, {.window = RpeWindow::kDistance, .delta = 2.0});
  EXPECT_EQ(r.pairs, 6u);
  EXPECT_NEAR(r.translation.mean, 8.75 / 6.0, 1e-12);
  EXPECT_NEAR(r.translation.max, 2.0, 1e-12);
  EXPECT_NEAR(r.translation.rmse, std::sqrt((1.0 + 2.25 + 1.0 + 4.0 + 3.0625 + 2.25) / 6.0), 1e-12);
  EXPECT_NEAR(r.rotation_deg.max, 0.0, 1e-12);
}

TEST(Rpe, TimeWindowOnTheSameData) {
  // delta = 2 s: pairs (i, i + 2) span 2 3 2.5 1 3.5 m, errors half of that.
  const StretchCase c = stretch_case();
  const RpeResult r = relative_pose_error(c.estimate, c.reference, {.window = RpeWindow::kTime, .delta = 2.0});
  EXPECT_EQ(r.pairs, 5u);
  EXPECT_NEAR(r.translation.mean, (1.0 + 1.5 + 1.25 + 0.5 + 1.75) / 5.0, 1e-12);
  EXPECT_NEAR(r.translation.max, 1.75, 1e-12);
}

TEST(Rpe, OutOfOrderStampsAreSortedFirst) {
  const StretchCase c = stretch_case();
  std::vector<StampedPose> shuffled(c.estimate.begin(), c.estimate.end());
  std::reverse(shuffled.begin(), shuffled.end());
  const RpeResult r =
      relative_pose_error(Trajectory(shuffled), c.reference, {.window = RpeWindow::kDistance, .delta = 2.0});
  EXPECT_EQ(r.pairs, 6u);
  EXPECT_NEAR(r.translation.mean, 8.75 / 6.0, 1e-12);
}

TEST(Rpe, NoWindowFitsAndBadInput) {
  const StretchCase c = stretch_case();
  const RpeResult none = relative_pose_error(c.estimate, c.reference, {.delta = 100.0});
  EXPECT_EQ(none.matched, 7u);
  EXPECT_EQ(none.pairs, 0u);
  EXPECT_EQ(none.translation.rmse, 0.0);
  EXPECT_THROW(relative_pose_error(c.estimate, c.reference, {.delta = 0.0}), Error);
  EXPECT_THROW(relative_pose_error(c.estimate, c.reference, {.delta = std::numeric_limits<double>::infinity()}), Error);
  EXPECT_THROW(relative_pose_error(c.estimate, c.reference, {.stamp_tolerance = -1.0}), Error);
}

}  // namespace
}  // namespace slam2d
