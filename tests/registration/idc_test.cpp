// SPDX-License-Identifier: BSD-3-Clause
// IMRP and IDC (Lu & Milios 1997, registration/idc.*): known transforms recovered from simulated
// scan pairs forward and inverse, a large rotation where closest-point ICP falls short, the range
// rule's rotation under a translation error, the building blocks against brute force and hand
// computation, refused inputs and configs.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <string>
#include <vector>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/registration/icp.hpp"
#include "slam2d/registration/idc.hpp"

namespace slam2d {
namespace {

struct PoseError {
  double translation = 0.0;  // m
  double rotation = 0.0;     // rad, absolute
};

PoseError pose_error(const SE2& estimate, const SE2& truth) {
  const SE2 error = truth.inverse() * estimate;
  return {error.translation().norm(), std::abs(normalize_angle(error.theta()))};
}

struct Case {
  std::string name;
  testing::ScanPair pair;
};

// The two scenes of the task: the office at the fixture's default pose, the room at (0.5, -0.3, 0.2).
std::vector<Case> scenes() {
  std::vector<Case> cases;
  cases.push_back({"office", testing::make_scan_pair(testing::office_world(), {})});
  cases.push_back({"room", testing::make_scan_pair(testing::room_world(), {.T_world_target = SE2(0.5, -0.3, 0.2)})});
  return cases;
}

// From the identity guess (the fixture's motion, 0.16 m and 0.05 rad) both ways. IMRP and IDC
// end on the noisy polylines within about 1 cm and 3 mrad here; the bounds leave a margin.
constexpr double kTranslationTolerance = 0.02;  // m
constexpr double kRotationTolerance = 0.008;    // rad

TEST(Imrp, RecoversKnownTransformsForwardAndInverse) {
  for (const Case& c : scenes()) {
    SCOPED_TRACE(c.name);
    const MatchResult forward = match_imrp(c.pair.target, c.pair.source, SE2());
    const PoseError f = pose_error(forward.T_target_source, c.pair.T_target_source);
    EXPECT_LT(f.translation, kTranslationTolerance);
    EXPECT_LT(f.rotation, kRotationTolerance);
    EXPECT_TRUE(forward.converged);
    EXPECT_FALSE(forward.degenerate);
    EXPECT_GT(forward.inliers, c.pair.source.size() * 3 / 4);
    const MatchResult inverse = match_imrp(c.pair.source, c.pair.target, SE2());
    const PoseError i = pose_error(inverse.T_target_source, c.pair.T_target_source.inverse());
    EXPECT_LT(i.translation, kTranslationTolerance);
    EXPECT_LT(i.rotation, kRotationTolerance);
    EXPECT_TRUE(inverse.converged);
  }
}

TEST(Idc, RecoversKnownTransformsForwardAndInverse) {
  for (const Case& c : scenes()) {
    SCOPED_TRACE(c.name);
    const MatchResult forward = match_idc(c.pair.target, c.pair.source, SE2());
    const PoseError f = pose_error(forward.T_target_source, c.pair.T_target_source);
    EXPECT_LT(f.translation, kTranslationTolerance);
    EXPECT_LT(f.rotation, kRotationTolerance);
    EXPECT_TRUE(forward.converged);
    EXPECT_FALSE(forward.degenerate);
    EXPECT_GT(forward.inliers, c.pair.source.size() * 3 / 4);
    EXPECT_GT(forward.residual, 0.0);
    EXPECT_LT(forward.residual, 0.03);  // 1 cm range noise on both scans
    const MatchResult inverse = match_idc(c.pair.source, c.pair.target, SE2());
    const PoseError i = pose_error(inverse.T_target_source, c.pair.T_target_source.inverse());
    EXPECT_LT(i.translation, kTranslationTolerance);
    EXPECT_LT(i.rotation, kRotationTolerance);
    EXPECT_TRUE(inverse.converged);
  }
}

// A 0.3 rad turn from the identity guess in the room: closest points pair the walls with their
// rotated neighbours and ICP stops short; the range rule pairs points at equal range across the
// bearing window and IDC finds the turn.
TEST(Idc, RecoversAThreeTenthsRadianTurnWhereClosestPointIcpFallsShort) {
  const testing::ScanPair pair = testing::make_scan_pair(
      testing::room_world(), {.T_world_target = SE2(0.5, -0.3, 0.2), .T_target_source = SE2(0.1, 0.05, 0.3)});
  const MatchResult icp = match_icp(pair.target, pair.source, SE2());
  const MatchResult idc = match_idc(pair.target, pair.source, SE2());
  const PoseError icp_error = pose_error(icp.T_target_source, pair.T_target_source);
  const PoseError idc_error = pose_error(idc.T_target_source, pair.T_target_source);
  EXPECT_GT(icp_error.rotation, 0.03);
  EXPECT_LT(idc_error.translation, kTranslationTolerance);
  EXPECT_LT(idc_error.rotation, kRotationTolerance);
}

// The range rule is made for rotation: a guess 0.15 m off in translation and 0.2 rad off in
// rotation still gives the rotation within a few mrad after IMRP (and the translation with it).
TEST(Imrp, GetsTheRotationRightDespiteATranslationErrorInTheGuess) {
  const testing::ScanPair pair = testing::make_scan_pair(testing::office_world(), {});
  const SE2 guess = pair.T_target_source * SE2(0.12, -0.09, 0.2);
  const MatchResult result = match_imrp(pair.target, pair.source, guess);
  const PoseError error = pose_error(result.T_target_source, pair.T_target_source);
  EXPECT_LT(error.rotation, kRotationTolerance);
  EXPECT_LT(error.translation, kTranslationTolerance);
}

// ---- Building blocks ----

TEST(IdcBlocks, FitRigidMotionRecoversAKnownMotionExactly) {
  const SE2 D(0.3, -0.2, 0.4);
  const std::vector<Point2> a{{1.0, 0.0}, {0.0, 2.0}, {-1.0, 0.5}, {2.0, 2.0}};
  std::vector<Point2> b;
  for (const Point2& p : a) b.push_back(D * p);
  const auto fitted = fit_rigid_motion(a, b);
  ASSERT_TRUE(fitted.has_value());
  EXPECT_NEAR(fitted->x(), 0.3, 1e-12);
  EXPECT_NEAR(fitted->y(), -0.2, 1e-12);
  EXPECT_NEAR(fitted->theta(), 0.4, 1e-12);
  // Hand-computed: two pairs a = (+-1, 0) -> b = (0, +-1) + (5, 0): a quarter turn, t = (5, 0).
  const auto quarter = fit_rigid_motion({{1.0, 0.0}, {-1.0, 0.0}}, {{5.0, 1.0}, {5.0, -1.0}});
  ASSERT_TRUE(quarter.has_value());
  EXPECT_NEAR(quarter->theta(), std::numbers::pi / 2.0, 1e-12);
  EXPECT_NEAR(quarter->x(), 5.0, 1e-12);
  EXPECT_NEAR(quarter->y(), 0.0, 1e-12);
  EXPECT_FALSE(fit_rigid_motion({{1.0, 0.0}}, {{1.0, 0.0}}).has_value());
}

// The projective search over the ordered polyline agrees with the linear search over every segment.
TEST(IdcBlocks, ClosestPointAgreesWithBruteForce) {
  const testing::ScanPair pair = testing::make_scan_pair(testing::office_world(), {});
  const ScanPolyline ordered = make_scan_polyline(pair.target, 0.5);
  ASSERT_TRUE(ordered.ordered);
  Rng rng(7);
  for (int k = 0; k < 500; ++k) {
    const Point2& base = pair.target.points[rng.uniform_index(pair.target.size())];
    const Point2 query = base + Point2(rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6));
    double best = 0.5;
    for (std::size_t j = 0; j < ordered.points.size(); ++j) {
      best = std::min(best, (ordered.points[j] - query).norm());
      if (j + 1 < ordered.points.size() && ordered.connected[j]) {
        const Point2 d = ordered.points[j + 1] - ordered.points[j];
        const double s = std::clamp((query - ordered.points[j]).dot(d) / d.squaredNorm(), 0.0, 1.0);
        best = std::min(best, (ordered.points[j] + s * d - query).norm());
      }
    }
    const auto found = closest_point(ordered, query, 0.5);
    if (best >= 0.5) {
      EXPECT_FALSE(found.has_value());
    } else {
      ASSERT_TRUE(found.has_value());
      EXPECT_NEAR(found->distance, best, 1e-12);
      EXPECT_NEAR((found->point - query).norm(), best, 1e-12);
    }
  }
}

// Under a pure rotation about the sensor every range is kept: the rule pairs each point with its
// own position on the target polyline (bearing difference = the rotation, range difference 0).
TEST(IdcBlocks, MatchingRangePointsAreExactUnderAPureRotation) {
  const testing::ScanPair pair = testing::make_scan_pair(testing::office_world(), {});
  const ScanPolyline polyline = make_scan_polyline(pair.target, 0.5);
  PointCloud2 source;
  const SE2 turn(0.0, 0.0, 0.05);
  for (std::size_t i = 0; i < polyline.points.size(); ++i) {
    if (i + 1 < polyline.points.size() && polyline.connected[i]) {
      source.points.push_back(turn.inverse() * (0.5 * (polyline.points[i] + polyline.points[i + 1])));
    }
  }
  const auto matches = matching_range_points(polyline, source, turn, 0.02, 0.1);
  std::size_t exact = 0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    if (!matches[i]) continue;
    if ((matches[i]->point - turn * source.points[i]).norm() < 1e-6) ++exact;
  }
  // A few midpoints see another crossing of their radius at a smaller bearing difference.
  EXPECT_GT(exact, source.size() * 9 / 10);
}

// ---- Refusals ----

TEST(IdcRefusals, EmptyAndTinyCloudsAreNotConverged) {
  const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), {.T_world_target = SE2(0.5, -0.3, 0.2)});
  const PointCloud2 empty;
  const PointCloud2 two{.points = {{1.0, 0.0}, {0.0, 1.0}}, .normals = {}, .weights = {}};
  for (const auto& [target, source] :
       {std::pair{&pair.target, &empty}, std::pair{&empty, &pair.source}, std::pair{&two, &two}}) {
    for (const MatchResult& result :
         {match_imrp(*target, *source, SE2(0.1, 0.0, 0.0)), match_idc(*target, *source, SE2(0.1, 0.0, 0.0))}) {
      EXPECT_FALSE(result.converged);
      EXPECT_GE(result.covariance.diagonal().minCoeff(), 1.0);
    }
  }
}

TEST(IdcRefusals, InvalidConfigsThrow) {
  EXPECT_THROW(validate(ImrpConfig{.max_iterations = 0}), Error);
  EXPECT_THROW(validate(ImrpConfig{.window_initial = 2.0}), Error);
  EXPECT_THROW(validate(ImrpConfig{.window_final = 0.5}), Error);  // above window_initial
  EXPECT_THROW(validate(ImrpConfig{.max_range_difference = 0.0}), Error);
  EXPECT_THROW(validate(ImrpConfig{.final_max_distance = -1.0}), Error);
  EXPECT_THROW(validate(IdcConfig{.max_distance_final = 2.0}), Error);
  EXPECT_THROW(validate(IdcConfig{.min_correspondences = 2}), Error);
  EXPECT_THROW(validate(IdcConfig{.range_sigma = std::nan("")}), Error);
  EXPECT_NO_THROW(validate(ImrpConfig{}));
  EXPECT_NO_THROW(validate(IdcConfig{}));
  const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), {});
  EXPECT_THROW(match_idc(pair.target, pair.source, SE2(), IdcConfig{.window_decay = -1.0}), Error);
}

}  // namespace
}  // namespace slam2d
