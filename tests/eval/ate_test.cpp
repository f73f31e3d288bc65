// SPDX-License-Identifier: BSD-3-Clause
// Tests of the absolute trajectory error (Sturm et al. 2012) and the closed-form 2D alignment.

#include "slam2d/eval/ate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::poses_near;

Trajectory random_walk(std::uint64_t seed, int poses) {
  Rng rng(seed);
  Trajectory trajectory;
  SE2 pose(1.0, 2.0, 0.3);
  for (int k = 0; k < poses; ++k) {
    trajectory.push_back(100.0 + 0.1 * k, pose);
    pose = pose * SE2(rng.uniform(0.0, 0.5), rng.uniform(-0.1, 0.1), rng.uniform(-0.4, 0.4));
  }
  return trajectory;
}

// Every pose of `trajectory` moved by T_new_old (a change of world frame).
Trajectory transformed(const Trajectory& trajectory, const SE2& T_new_old) {
  Trajectory result;
  for (const StampedPose& p : trajectory) result.push_back(p.stamp, T_new_old * p.pose);
  return result;
}

TEST(Ate, RecoversAKnownRigidTransformExactly) {
  const Trajectory reference = random_walk(7, 200);
  for (const SE2& T_reference_estimate : {SE2(3.0, -4.0, 2.5), SE2(-50.0, 20.0, -3.1), SE2(0.0, 0.0, 0.0)}) {
    const Trajectory estimate = transformed(reference, T_reference_estimate.inverse());
    const AteResult r = absolute_trajectory_error(estimate, reference);
    EXPECT_EQ(r.matched, 200u);
    EXPECT_TRUE(poses_near(r.T_reference_estimate, T_reference_estimate, 1e-9, 1e-12));
    EXPECT_LT(r.rmse, 1e-9);
    EXPECT_LT(r.max, 1e-9);
  }
}

TEST(Ate, HandComputedScaledCopy) {
  // Reference on the x axis at -3, -1, 0, 1, 3; estimate stretched by 1.5 about the centroid and
  // then moved to another world frame. The best rigid alignment undoes only the frame change
  // (a stretch about the centroid has no rotational or translational component), leaving errors
  // 1.5, 0.5, 0, 0.5, 1.5: rmse sqrt((2 * 2.25 + 2 * 0.25) / 5) = 1, mean 0.8, median 0.5, max 1.5.
  const std::vector<double> xs{-3.0, -1.0, 0.0, 1.0, 3.0};
  const SE2 T_estimate_reference(7.0, -2.0, 1.0);
  Trajectory reference;
  Trajectory estimate;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    reference.push_back(static_cast<double>(k), SE2(xs[k], 0.0, 0.2 * static_cast<double>(k)));
    estimate.push_back(static_cast<double>(k), T_estimate_reference * SE2(1.5 * xs[k], 0.0, 0.0));
  }
  const AteResult r = absolute_trajectory_error(estimate, reference);
  EXPECT_EQ(r.matched, 5u);
  EXPECT_TRUE(poses_near(r.T_reference_estimate, T_estimate_reference.inverse(), 1e-12, 1e-12));
  EXPECT_NEAR(r.rmse, 1.0, 1e-12);
  EXPECT_NEAR(r.mean, 0.8, 1e-12);
  EXPECT_NEAR(r.median, 0.5, 1e-12);
  EXPECT_NEAR(r.max, 1.5, 1e-12);
  ASSERT_EQ(r.errors.size(), 5u);
  EXPECT_NEAR(r.errors[2], 0.0, 1e-12);
}

TEST(Ate, AssociatesByStampWhateverTheOrder) {
  const Trajectory reference = random_walk(11, 50);
  const SE2 T_estimate_reference(1.0, 1.0, -0.7);
  std::vector<StampedPose> poses;
  for (const StampedPose& p : reference) {
    poses.push_back({p.stamp + 0.0004, T_estimate_reference * p.pose});  // within 1 ms
  }
  poses.push_back({5.0, SE2(1e3, 1e3, 0.0)});  // no reference pose near: not matched
  std::reverse(poses.begin(), poses.end());
  const AteResult r = absolute_trajectory_error(Trajectory(poses), reference);
  EXPECT_EQ(r.matched, 50u);
  EXPECT_LT(r.rmse, 1e-9);
  EXPECT_TRUE(poses_near(r.T_reference_estimate, T_estimate_reference.inverse(), 1e-9, 1e-12));
}

TEST(Ate, ThrowsWhenTooFewPosesAssociate) {
  const Trajectory reference = random_walk(3, 10);
  Trajectory estimate;
  estimate.push_back(100.0, SE2());
  EXPECT_THROW(absolute_trajectory_error(estimate, reference), Error);  // 1 match
  EXPECT_THROW(absolute_trajectory_error(transformed(reference, SE2()), reference, {.stamp_tolerance = -0.1}), Error);
  Trajectory shifted;
  for (const StampedPose& p : reference) shifted.push_back(p.stamp + 1000.0, p.pose);
  EXPECT_THROW(absolute_trajectory_error(shifted, reference), Error);  // time bases differ
}

TEST(AlignRigid2d, MatchesAKnownTransformAndHandlesDegenerateInput) {
  const std::vector<Eigen::Vector2d> source{{0.0, 0.0}, {1.0, 0.0}, {0.0, 2.0}};
  const SE2 T(0.5, -0.25, 2.0);
  std::vector<Eigen::Vector2d> target;
  for (const auto& p : source) target.push_back(T * p);
  EXPECT_TRUE(poses_near(align_rigid_2d(source, target), T, 1e-12, 1e-12));
  // One point, or all points at the same place: any rotation fits, the angle is 0.
  const SE2 single = align_rigid_2d({{1.0, 1.0}}, {{4.0, 5.0}});
  EXPECT_TRUE(poses_near(single, SE2(3.0, 4.0, 0.0), 1e-12, 1e-12));
  EXPECT_THROW(align_rigid_2d({}, {}), Error);
  EXPECT_THROW(align_rigid_2d({{0.0, 0.0}}, {{0.0, 0.0}, {1.0, 1.0}}), Error);
}

}  // namespace
}  // namespace slam2d
