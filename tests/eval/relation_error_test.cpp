// SPDX-License-Identifier: BSD-3-Clause
// Tests of the relation error of Kuemmerle et al. 2009 on hand-computed cases.

#include "slam2d/eval/relation_error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

constexpr double kPi = std::numbers::pi;

Relation make_relation(double t1, double t2, const SE2& T_from_to) { return {t1, t2, T_from_to, 0}; }

// A truth trajectory with steps `truth_step` at stamps 0, 1, 2, ... and an estimate whose every step
// is truth_step * step_error, so that each consecutive relation has the error step_error exactly.
struct ConstantErrorCase {
  Trajectory estimate;
  std::vector<Relation> relations;
};

ConstantErrorCase constant_error_case(const SE2& truth_step, const SE2& step_error, int steps) {
  ConstantErrorCase c;
  SE2 pose = SE2(3.0, -2.0, 0.4);
  c.estimate.push_back(0.0, pose);
  for (int k = 1; k <= steps; ++k) {
    pose = pose * truth_step * step_error;
    c.estimate.push_back(k, pose);
    c.relations.push_back(make_relation(k - 1, k, truth_step));
  }
  return c;
}

TEST(RelationError, ConstantErrorPerStep) {
  const SE2 step_error(0.03, -0.04, 0.02);  // 0.05 m, 0.02 rad
  const auto c = constant_error_case(SE2(1.0, 0.2, 0.3), step_error, 20);
  const RelationErrorResult r = relation_error(c.estimate, c.relations);
  EXPECT_EQ(r.relations, 20u);
  EXPECT_EQ(r.missing, 0u);
  ASSERT_EQ(r.errors.size(), 20u);
  for (std::size_t k = 0; k < r.errors.size(); ++k) {
    EXPECT_EQ(r.errors[k].relation_index, k);
    EXPECT_NEAR(r.errors[k].translation, 0.05, 1e-12);
    EXPECT_NEAR(r.errors[k].rotation, 0.02, 1e-12);
  }
  EXPECT_NEAR(r.translation.mean, 0.05, 1e-12);
  EXPECT_NEAR(r.translation.std, 0.0, 1e-12);
  EXPECT_NEAR(r.translation.max, 0.05, 1e-12);
  EXPECT_NEAR(r.rotation_deg.mean, rad_to_deg(0.02), 1e-10);
  EXPECT_NEAR(r.translation_squared.mean, 0.0025, 1e-12);
  EXPECT_NEAR(r.rotation_squared_deg2.mean, rad_to_deg(0.02) * rad_to_deg(0.02), 1e-9);
}

TEST(RelationError, MeanStdMaxOfDifferentErrors) {
  // Two relations with pure translational errors of 0.1 m and 0.3 m, one with a pure 2 degree
  // rotational error: mean 0.4/3, population std sqrt(((0.1-m)^2 + (0.3-m)^2 + m^2) / 3).
  Trajectory estimate;
  estimate.push_back(0.0, SE2(0.0, 0.0, 0.0));
  estimate.push_back(1.0, SE2(1.1, 0.0, 0.0));
  estimate.push_back(2.0, SE2(1.1, 2.3, 0.0));
  estimate.push_back(3.0, SE2(1.1, 2.3, deg_to_rad(2.0)));
  const std::vector<Relation> relations{make_relation(0.0, 1.0, SE2(1.0, 0.0, 0.0)),
                                        make_relation(1.0, 2.0, SE2(0.0, 2.0, 0.0)),
                                        make_relation(2.0, 3.0, SE2(0.0, 0.0, 0.0))};
  const RelationErrorResult r = relation_error(estimate, relations);
  ASSERT_EQ(r.relations, 3u);
  const double m = 0.4 / 3.0;
  EXPECT_NEAR(r.translation.mean, m, 1e-12);
  EXPECT_NEAR(r.translation.std, std::sqrt(((0.1 - m) * (0.1 - m) + (0.3 - m) * (0.3 - m) + m * m) / 3.0), 1e-12);
  EXPECT_NEAR(r.translation.max, 0.3, 1e-12);
  EXPECT_NEAR(r.rotation_deg.mean, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(r.rotation_deg.max, 2.0, 1e-12);
  EXPECT_NEAR(r.rotation_deg.std, std::sqrt((2.0 * (2.0 / 3.0) * (2.0 / 3.0) + (4.0 / 3.0) * (4.0 / 3.0)) / 3.0),
              1e-12);
  EXPECT_NEAR(r.translation_squared.mean, (0.01 + 0.09) / 3.0, 1e-12);
  EXPECT_NEAR(r.translation_squared.max, 0.09, 1e-12);
  EXPECT_NEAR(r.rotation_squared_deg2.mean, 4.0 / 3.0, 1e-10);
  EXPECT_NEAR(r.rotation_squared_deg2.max, 4.0, 1e-10);
}

TEST(RelationError, ErrorIsExpressedInTheFrameOfTheTruthRelation) {
  // Truth: 2 m ahead, turned by 90 degrees. Estimate: 2 m ahead and 0.1 m to the left, turned by
  // 90 degrees. D = T^-1 E = (0.1, 0, 0): the 0.1 m offset, seen from the truth's end pose.
  Trajectory estimate;
  estimate.push_back(5.0, SE2(10.0, 10.0, kPi / 2));
  estimate.push_back(6.0, SE2(10.0 - 0.1, 12.0, kPi));
  const RelationErrorResult r = relation_error(estimate, {make_relation(5.0, 6.0, SE2(2.0, 0.0, kPi / 2))});
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NEAR(r.errors[0].translation, 0.1, 1e-12);
  EXPECT_NEAR(r.errors[0].rotation, 0.0, 1e-12);
}

TEST(RelationError, RotationErrorWrapsNearPi) {
  // Truth turns by pi - 0.01, estimate by -pi + 0.01 (i.e. pi + 0.01): the error is 0.02 rad, not
  // 2 pi - 0.02.
  Trajectory estimate;
  estimate.push_back(0.0, SE2(0.0, 0.0, 0.0));
  estimate.push_back(1.0, SE2(0.0, 0.0, -kPi + 0.01));
  estimate.push_back(2.0, SE2(0.0, 0.0, kPi - 0.001));  // relative to stamp 0: almost a half turn
  estimate.push_back(3.0, SE2(0.0, 0.0, kPi));          // stored as -pi
  const std::vector<Relation> relations{make_relation(0.0, 1.0, SE2(0.0, 0.0, kPi - 0.01)),
                                        make_relation(0.0, 2.0, SE2(0.0, 0.0, 0.0)),
                                        make_relation(0.0, 3.0, SE2(0.0, 0.0, 0.0))};
  const RelationErrorResult r = relation_error(estimate, relations);
  ASSERT_EQ(r.errors.size(), 3u);
  EXPECT_NEAR(r.errors[0].rotation, 0.02, 1e-12);
  EXPECT_NEAR(r.errors[1].rotation, kPi - 0.001, 1e-12);
  EXPECT_NEAR(r.errors[2].rotation, kPi, 1e-12);  // a half turn is pi, positive
  EXPECT_NEAR(r.rotation_deg.max, 180.0, 1e-9);
}

TEST(RelationError, MissingPosesAreCountedAndLeftOut) {
  auto c = constant_error_case(SE2(1.0, 0.0, 0.1), SE2(0.2, 0.0, 0.0), 4);
  c.relations.insert(c.relations.begin() + 1, make_relation(1.0, 7.0, SE2()));  // 7: no pose
  c.relations.push_back(make_relation(-3.0, 2.0, SE2()));                       // -3: no pose
  const RelationErrorResult r = relation_error(c.estimate, c.relations);
  EXPECT_EQ(r.relations, 4u);
  EXPECT_EQ(r.missing, 2u);
  ASSERT_EQ(r.errors.size(), 4u);
  EXPECT_EQ(r.errors[0].relation_index, 0u);
  EXPECT_EQ(r.errors[1].relation_index, 2u);
  EXPECT_EQ(r.errors[3].relation_index, 4u);
  EXPECT_NEAR(r.translation.mean, 0.2, 1e-12);  // the missing ones do not dilute the statistics
}

TEST(RelationError, OutOfOrderTrajectoryStampsGiveTheSameResult) {
  const auto c = constant_error_case(SE2(0.5, 0.1, -0.2), SE2(0.01, 0.02, -0.03), 12);
  std::vector<StampedPose> shuffled(c.estimate.begin(), c.estimate.end());
  std::reverse(shuffled.begin(), shuffled.end());
  std::swap(shuffled[2], shuffled[9]);
  const Trajectory out_of_order(shuffled);
  ASSERT_FALSE(out_of_order.is_monotonic());
  const RelationErrorResult a = relation_error(c.estimate, c.relations);
  const RelationErrorResult b = relation_error(out_of_order, c.relations);
  ASSERT_EQ(b.relations, 12u);
  for (std::size_t k = 0; k < a.errors.size(); ++k) {
    EXPECT_EQ(a.errors[k].translation, b.errors[k].translation);
    EXPECT_EQ(a.errors[k].rotation, b.errors[k].rotation);
  }
  EXPECT_NEAR(b.translation.mean, std::hypot(0.01, 0.02), 1e-12);
}

TEST(RelationError, StampToleranceBoundaryIsInclusive) {
  Trajectory estimate;
  estimate.push_back(10.0, SE2(0.0, 0.0, 0.0));
  estimate.push_back(20.25, SE2(1.0, 0.0, 0.0));  // 0.25 s after the relation's stamp
  const std::vector<Relation> relations{make_relation(10.0, 20.0, SE2(1.0, 0.0, 0.0))};
  EXPECT_EQ(relation_error(estimate, relations, {.stamp_tolerance = 0.25}).relations, 1u);
  const RelationErrorResult outside = relation_error(estimate, relations, {.stamp_tolerance = 0.2499});
  EXPECT_EQ(outside.relations, 0u);
  EXPECT_EQ(outside.missing, 1u);
  EXPECT_EQ(outside.translation.mean, 0.0);                    // nothing evaluated: zeros
  EXPECT_EQ(relation_error(estimate, relations).missing, 1u);  // default 1 ms
}

TEST(RelationError, NearestStampWins) {
  Trajectory estimate;
  estimate.push_back(0.0, SE2(0.0, 0.0, 0.0));
  estimate.push_back(1.0004, SE2(5.0, 0.0, 0.0));  // 0.4 ms after
  estimate.push_back(0.9998, SE2(1.0, 0.0, 0.0));  // 0.2 ms before: nearer
  const RelationErrorResult r = relation_error(estimate, {make_relation(0.0, 1.0, SE2(1.0, 0.0, 0.0))});
  ASSERT_EQ(r.relations, 1u);
  EXPECT_NEAR(r.errors[0].translation, 0.0, 1e-12);
}

TEST(RelationError, PerfectEstimateHasZeroError) {
  const auto c = constant_error_case(SE2(0.7, -0.3, 1.3), SE2(), 30);
  const RelationErrorResult r = relation_error(c.estimate, c.relations);
  EXPECT_EQ(r.relations, 30u);
  EXPECT_LT(r.translation.max, 1e-12);
  EXPECT_LT(r.rotation_deg.max, 1e-10);
}

TEST(RelationError, RejectsBadInput) {
  const auto c = constant_error_case(SE2(1.0, 0.0, 0.0), SE2(), 2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(relation_error(c.estimate, c.relations, {.stamp_tolerance = -1.0}), Error);
  EXPECT_THROW(relation_error(c.estimate, c.relations, {.stamp_tolerance = nan}), Error);
  EXPECT_THROW(relation_error(c.estimate, {make_relation(nan, 1.0, SE2())}), Error);
  EXPECT_THROW(relation_error(c.estimate, {make_relation(0.0, 1.0, SE2(nan, 0.0, 0.0))}), Error);
  Trajectory bad = c.estimate;
  bad.push_back(nan, SE2());
  EXPECT_THROW(relation_error(bad, c.relations), Error);
  const RelationErrorResult empty = relation_error(Trajectory(), c.relations);
  EXPECT_EQ(empty.relations, 0u);
  EXPECT_EQ(empty.missing, 2u);
}

}  // namespace
}  // namespace slam2d
