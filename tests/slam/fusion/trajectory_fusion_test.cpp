// SPDX-License-Identifier: BSD-3-Clause
// The dense/sparse trajectory fusion (slam/fusion): it passes through every sparse pose, leaves a
// dense trajectory that already agrees alone, removes a drifting dense trajectory's drift while
// keeping its local shape, and refuses what it cannot fuse.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/slam/fusion/trajectory_fusion.hpp"

namespace slam2d {
namespace {

// A wavy path at 10 Hz, 60 s.
Trajectory truth() {
  Trajectory path;
  for (int i = 0; i <= 600; ++i) {
    const double t = 0.1 * i;
    path.push_back(t, SE2(0.5 * t, 2.0 * std::sin(0.2 * t), std::atan2(0.4 * std::cos(0.2 * t), 0.5)));
  }
  return path;
}

// Its odometry with a 2% scale error and a heading drift of 0.02 rad per metre: a dense
// trajectory that is right locally and wrong globally.
Trajectory drifting(const Trajectory& path) {
  Trajectory dense;
  SE2 pose = path[0].pose;
  dense.push_back(path[0].stamp, pose);
  for (std::size_t i = 1; i < path.size(); ++i) {
    const SE2 step = path[i - 1].pose.between(path[i].pose);
    const double length = step.translation().norm();
    pose = pose * SE2(1.02 * step.x(), 1.02 * step.y(), step.theta() + 0.02 * length);
    dense.push_back(path[i].stamp, pose);
  }
  return dense;
}

Trajectory every(const Trajectory& path, std::size_t n) {
  Trajectory sparse;
  for (std::size_t i = 0; i < path.size(); i += n) sparse.push_back(path[i].stamp, path[i].pose);
  return sparse;
}

// The paper's fusion: a similarity per segment, through every sparse pose.
constexpr FusionConfig kPaper{.alignment = FusionAlignment::kSimilarity, .correction_smoothing = 0.0};

double max_error(const Trajectory& a, const Trajectory& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i].pose.translation() - b[i].pose.translation()).norm());
  return worst;
}

TEST(TrajectoryFusion, ADenseTrajectoryThatAgreesIsLeftAsItIs) {
  const Trajectory path = truth();
  FusionStats stats;
  const Trajectory fused = fuse_trajectories(path, every(path, 20), kPaper, &stats);
  ASSERT_EQ(fused.size(), path.size());
  EXPECT_LT(max_error(fused, path), 1e-9);
  for (std::size_t i = 0; i < path.size(); ++i) EXPECT_NEAR(fused[i].pose.theta(), path[i].pose.theta(), 1e-9) << i;
  EXPECT_EQ(stats.sparse_used, 31u);
  EXPECT_EQ(stats.segments, 30u);
  EXPECT_LT(stats.max_scale_change, 1e-9);
}

TEST(TrajectoryFusion, TheDriftGoesAndTheLocalShapeStays) {
  const Trajectory path = truth();
  const Trajectory dense = drifting(path);
  const Trajectory sparse = every(path, 20);
  FusionStats stats;
  const Trajectory fused = fuse_trajectories(dense, sparse, kPaper, &stats);
  ASSERT_EQ(fused.size(), dense.size());
  EXPECT_GT(max_error(dense, path), 3.0) << "the dense trajectory drifts metres away";
  EXPECT_LT(max_error(fused, path), 0.05) << "the fused one stays within 5 cm";
  for (std::size_t i = 0; i < path.size(); i += 20) {  // through every sparse pose
    EXPECT_NEAR((fused[i].pose.translation() - path[i].pose.translation()).norm(), 0.0, 1e-9) << i;
    EXPECT_NEAR(normalize_angle(fused[i].pose.theta() - path[i].pose.theta()), 0.0, 1e-9) << i;
  }
  double worst_step = 0.0;  // each 0.1 s step of the fused path, against the truth's
  for (std::size_t i = 1; i < path.size(); ++i) {
    const SE2 fused_step = fused[i - 1].pose.between(fused[i].pose);
    const SE2 true_step = path[i - 1].pose.between(path[i].pose);
    worst_step = std::max(worst_step, (fused_step.translation() - true_step.translation()).norm());
  }
  EXPECT_LT(worst_step, 0.005);
  EXPECT_GT(stats.max_scale_change, 0.005);
  EXPECT_EQ(stats.blended_segments, 0u);
}

TEST(TrajectoryFusion, PosesOutsideTheSparseSpanMoveRigidlyAndAStandingRobotIsRigid) {
  Trajectory dense;
  for (int i = 0; i <= 10; ++i) dense.push_back(i, SE2(i < 5 ? 0.1 * i : 0.5, 0.0, 0.0));  // stands from t = 5
  Trajectory sparse;
  sparse.push_back(5.0, SE2(1.0, 1.0, 0.5));
  sparse.push_back(8.0, SE2(1.0, 1.0, 0.5));
  FusionStats stats;
  const Trajectory fused = fuse_trajectories(dense, sparse, kPaper, &stats);
  EXPECT_EQ(stats.blended_segments, 1u);
  const SE2 correction = SE2(1.0, 1.0, 0.5) * SE2(0.5, 0.0, 0.0).inverse();
  for (int i = 0; i <= 10; ++i) {
    const SE2 expected = correction * dense[static_cast<std::size_t>(i)].pose;
    EXPECT_NEAR((fused[static_cast<std::size_t>(i)].pose.translation() - expected.translation()).norm(), 0.0, 1e-12) << i;
    EXPECT_NEAR(fused[static_cast<std::size_t>(i)].pose.theta(), expected.theta(), 1e-12) << i;
  }
}

double mean_error(const Trajectory& a, const Trajectory& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (a[i].pose.translation() - b[i].pose.translation()).norm();
  return sum / static_cast<double>(a.size());
}

// The largest difference between a's and b's steps over `lag` poses: how much of the local shape
// is lost.
double max_step_error(const Trajectory& a, const Trajectory& b, std::size_t lag) {
  double worst = 0.0;
  for (std::size_t i = lag; i < a.size(); ++i) {
    const SE2 da = a[i - lag].pose.between(a[i].pose);
    const SE2 db = b[i - lag].pose.between(b[i].pose);
    worst = std::max(worst, (da.translation() - db.translation()).norm());
  }
  return worst;
}

TEST(TrajectoryFusion, InterpolatedCorrectionsAlsoRemoveTheDriftThroughEverySparsePose) {
  const Trajectory path = truth();
  const Trajectory dense = drifting(path);
  FusionStats stats;
  const Trajectory fused = fuse_trajectories(dense, every(path, 20), {.correction_smoothing = 0.0}, &stats);
  EXPECT_EQ(stats.blended_segments, stats.segments);
  EXPECT_LT(max_error(fused, path), 0.05);
  for (std::size_t i = 0; i < path.size(); i += 20) {
    EXPECT_NEAR((fused[i].pose.translation() - path[i].pose.translation()).norm(), 0.0, 1e-9) << i;
  }
  EXPECT_LT(max_step_error(fused, path, 1), 0.005);
}

TEST(TrajectoryFusion, SmoothedCorrectionsKeepNoisySparsePosesFromBendingTheDensePath) {
  // The dense trajectory is the truth; the sparse one (3 Hz) has 2 cm of seeded noise per pose.
  const Trajectory path = truth();
  Trajectory noisy;
  std::uint64_t state = 12345;
  const auto noise = [&state] {  // a small LCG: uniform in [-0.02, 0.02] m
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return 0.04 * (static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5);
  };
  for (std::size_t i = 0; i < path.size(); i += 3) {
    const SE2& pose = path[i].pose;
    noisy.push_back(path[i].stamp, SE2(pose.x() + noise(), pose.y() + noise(), pose.theta()));
  }
  const Trajectory exact = fuse_trajectories(path, noisy, {.correction_smoothing = 0.0});
  const Trajectory smoothed = fuse_trajectories(path, noisy, {.correction_smoothing = 0.5});
  EXPECT_GT(mean_error(exact, path), 0.007) << "through every noisy pose";
  EXPECT_LT(mean_error(smoothed, path), 0.5 * mean_error(exact, path));
  EXPECT_LT(max_step_error(smoothed, path, 2), 0.5 * max_step_error(exact, path, 2)) << "the local shape is kept";
  // The drift still goes: smoothing over 0.5 s does not hold back a correction that grows over metres.
  const Trajectory drifted = fuse_trajectories(drifting(path), noisy, {.correction_smoothing = 0.5});
  EXPECT_LT(max_error(drifted, path), 0.05);
}

TEST(TrajectoryFusion, ACorrectionChangesOnlyWhileTheRobotMoves) {
  // The robot stands for 2 s, then drives 1 m in 1 s; the sparse poses say the drive was 10 cm
  // longer. The correction must be spent over the drive: interpolated in time, two thirds of it
  // would move the standing robot (6.7 cm of motion that never happened).
  Trajectory dense;
  for (int i = 0; i <= 30; ++i) dense.push_back(0.1 * i, SE2(i <= 20 ? 0.0 : 0.1 * (i - 20), 0.0, 0.0));
  Trajectory sparse;
  sparse.push_back(0.0, SE2(0.0, 0.0, 0.0));
  sparse.push_back(3.0, SE2(1.1, 0.0, 0.0));
  const Trajectory fused = fuse_trajectories(dense, sparse, {.correction_smoothing = 0.0});
  for (std::size_t i = 0; i <= 20; ++i) EXPECT_NEAR(fused[i].pose.x(), 0.0, 1e-12) << "standing, " << i;
  for (std::size_t i = 21; i <= 30; ++i) EXPECT_NEAR(fused[i].pose.x(), 0.11 * static_cast<double>(i - 20), 1e-12) << i;
  // A turn in place has no distance: there the correction goes in time.
  Trajectory turn;
  for (int i = 0; i <= 10; ++i) turn.push_back(0.1 * i, SE2(0.0, 0.0, 0.1 * i));
  Trajectory turned;
  turned.push_back(0.0, SE2(0.0, 0.0, 0.0));
  turned.push_back(1.0, SE2(0.0, 0.0, 1.2));
  const Trajectory in_place = fuse_trajectories(turn, turned, {.correction_smoothing = 0.0});
  for (std::size_t i = 0; i <= 10; ++i) EXPECT_NEAR(in_place[i].pose.theta(), 0.12 * static_cast<double>(i), 1e-12) << i;
}

TEST(TrajectoryFusion, RefusesWhatItCannotFuse) {
  const Trajectory path = truth();
  EXPECT_THROW(fuse_trajectories(Trajectory(), path), Error);
  EXPECT_THROW(fuse_trajectories(path, Trajectory()), Error);
  EXPECT_THROW(fuse_trajectories(path, path, {.correction_smoothing = -1.0}), Error);
  Trajectory later;
  later.push_back(1000.0, SE2());
  EXPECT_THROW(fuse_trajectories(path, later), Error);
}

}  // namespace
}  // namespace slam2d
