// SPDX-License-Identifier: BSD-3-Clause
// Hector's jumps smoothed (slam/fusion/discontinuity_smoothing): injected jumps are found and
// replaced by the motion before them, a trajectory without jumps is left as it is (a robot that
// starts, stops and turns included), and a gap in the log is not a jump.

#include <gtest/gtest.h>

#include <cmath>

#include "slam2d/core/error.hpp"
#include "slam2d/slam/fusion/discontinuity_smoothing.hpp"

namespace slam2d {
namespace {

// 10 Hz: 10 s standing, 20 s at 0.5 m/s along a slow curve, a turn in place at 0.6 rad/s, 10 s at
// 0.5 m/s again.
Trajectory drive() {
  Trajectory path;
  SE2 pose;
  for (int i = 0; i <= 500; ++i) {
    const double t = 0.1 * i;
    SE2 step;
    if (t > 10.0 && t <= 30.0) step = SE2(0.05, 0.0, 0.005);
    if (t > 30.0 && t <= 35.0) step = SE2(0.0, 0.0, 0.06);
    if (t > 35.0) step = SE2(0.05, 0.0, 0.0);
    pose = pose * step;
    path.push_back(t, pose);
  }
  return path;
}

// The path with a scan-matcher's excursion: at step `at` the pose jumps by `jump` (in its own
// frame) and at `at + hold` it jumps back; every step in between is the path's.
Trajectory with_excursion(const Trajectory& path, std::size_t at, std::size_t hold, const SE2& jump) {
  Trajectory jumped;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const bool away = i >= at && i < at + hold;
    jumped.push_back(path[i].stamp, away ? path[i].pose * jump : path[i].pose);
  }
  return jumped;
}

double max_distance(const Trajectory& a, const Trajectory& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i].pose.translation() - b[i].pose.translation()).norm());
  return worst;
}

TEST(DiscontinuitySmoothing, ATrajectoryWithoutJumpsIsLeftAsItIs) {
  const Trajectory path = drive();
  const SmoothingResult result = smooth_discontinuities(path);
  EXPECT_TRUE(result.jumps.empty());
  EXPECT_LT(max_distance(result.trajectory, path), 1e-9);
}

TEST(DiscontinuitySmoothing, JumpsAreReplacedByTheMeanOfThePrecedingSteps) {
  const Trajectory path = drive();
  // A 0.6 m sideways jump while driving, back 5 scans later; a 0.8 rad heading jump while standing.
  Trajectory jumped = with_excursion(path, 200, 5, SE2(0.0, 0.6, 0.0));
  jumped = with_excursion(jumped, 50, 3, SE2(0.0, 0.0, 0.8));
  ASSERT_GT(max_distance(jumped, path), 0.55);
  const SmoothingResult result = smooth_discontinuities(jumped);
  ASSERT_EQ(result.jumps.size(), 4u);  // into and out of each excursion
  EXPECT_EQ(result.jumps[0], 50u);
  EXPECT_EQ(result.jumps[1], 53u);
  EXPECT_EQ(result.jumps[2], 200u);
  EXPECT_EQ(result.jumps[3], 205u);
  // Each replaced step is the mean motion before it, so the path comes back within a few
  // centimetres of the truth (the steps inside the excursion are the true ones).
  EXPECT_LT(max_distance(result.trajectory, path), 0.03);
  ASSERT_EQ(result.trajectory.size(), path.size());
  for (std::size_t i = 0; i < path.size(); ++i) EXPECT_EQ(result.trajectory[i].stamp, path[i].stamp);
}

TEST(DiscontinuitySmoothing, AGapInTheLogIsNotAJump) {
  Trajectory path;
  for (int i = 0; i < 50; ++i) path.push_back(0.1 * i, SE2(0.05 * i, 0.0, 0.0));
  for (int i = 0; i < 50; ++i) path.push_back(20.0 + 0.1 * i, SE2(10.0 + 0.05 * i, 0.0, 0.0));  // 15 s, 7.5 m later
  const SmoothingResult result = smooth_discontinuities(path);
  EXPECT_TRUE(result.jumps.empty());
  EXPECT_LT(max_distance(result.trajectory, path), 1e-9);
}

TEST(DiscontinuitySmoothing, RefusesABadConfig) {
  EXPECT_THROW(smooth_discontinuities(drive(), {.window = 0}), Error);
  EXPECT_THROW(smooth_discontinuities(drive(), {.factor = 0.5}), Error);
  EXPECT_THROW(smooth_discontinuities(drive(), {.min_jump = std::nan("")}), Error);
}

}  // namespace
}  // namespace slam2d
