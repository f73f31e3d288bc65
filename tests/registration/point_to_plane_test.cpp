// SPDX-License-Identifier: BSD-3-Clause
// Point-to-plane ICP by linear least squares (Low 2004, src/slam2d/registration/point_to_plane.*
// and solve_point_to_plane in closed_form.*): the small-angle linear step against the exact
// point-to-line minimiser (Censi 2008's closed form, pl_icp.hpp), known transforms recovered
// from simulated scan pairs forward and inverse, normals estimated when the target has none,
// the corridor flagged degenerate along its axis, and bad input never passed off as success.

#include "slam2d/registration/point_to_plane.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/registration/closed_form.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::poses_near;

// ---------------------------------------------------------------------------------------------
// The linear step (Low 2004) on fixed pairs.

/// Pairs (d_i, n_i, s_i) with s_i on the line through d_i along n_i's tangent, moved by the
/// inverse of T_true, plus `sigma` of noise along the normal: T_true minimises the point-to-plane
/// cost exactly when sigma = 0.
struct PlanePairs {
  std::vector<Point2> targets;
  std::vector<Point2> normals;
  std::vector<Point2> sources;
};

PlanePairs random_plane_pairs(Rng& rng, const SE2& T_true, double sigma, int count) {
  PlanePairs pairs;
  const SE2 T_inverse = T_true.inverse();
  for (int i = 0; i < count; ++i) {
    const Point2 d(rng.uniform(-5.0, 5.0), rng.uniform(-5.0, 5.0));
    const double angle = rng.uniform(-std::numbers::pi, std::numbers::pi);
    const Point2 n(std::cos(angle), std::sin(angle));
    const Point2 on_line = d + rng.uniform(-0.5, 0.5) * Point2(-n.y(), n.x()) + rng.gaussian(0.0, sigma) * n;
    pairs.targets.push_back(d);
    pairs.normals.push_back(n);
    pairs.sources.push_back(T_inverse * on_line);
  }
  return pairs;
}

/// The exact minimiser of sum (n_i . (T s_i - d_i))^2 over SE2: Censi's closed form.
SE2 exact_minimum(const PlanePairs& pairs) {
  PointToLineProblem problem;
  for (std::size_t i = 0; i < pairs.sources.size(); ++i) problem.add(pairs.sources[i], pairs.targets[i], pairs.normals[i]);
  const std::optional<SE2> minimum = minimize_point_to_line(problem);
  EXPECT_TRUE(minimum.has_value());
  return minimum.value_or(SE2());
}

/// One linear step at T (the source moved by T, the increment composed on the left).
SE2 linear_step(const PlanePairs& pairs, const SE2& T) {
  std::vector<Point2> moved;
  for (const Point2& s : pairs.sources) moved.push_back(T * s);
  const std::optional<SE2> increment = solve_point_to_plane(pairs.targets, pairs.normals, moved);
  EXPECT_TRUE(increment.has_value());
  return increment.value_or(SE2()) * T;
}

double pose_distance(const SE2& a, const SE2& b) {
  return std::max((a.translation() - b.translation()).norm(), std::abs(angle_difference(a.theta(), b.theta())));
}

TEST(PointToPlaneStep, NoiseFreePairsWithoutRotationGiveTheTranslationExactly) {
  Rng rng(1);
  const PlanePairs pairs = random_plane_pairs(rng, SE2(0.4, -0.3, 0.0), 0.0, 30);
  EXPECT_TRUE(poses_near(linear_step(pairs, SE2()), SE2(0.4, -0.3, 0.0), 1e-12, 1e-12));
}

TEST(PointToPlaneStep, EqualsTheExactMinimiserForTinyRotationsWithASecondOrderError) {
  Rng rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    const double x = rng.uniform(-0.3, 0.3);
    const double y = rng.uniform(-0.3, 0.3);
    const PlanePairs tiny = random_plane_pairs(rng, SE2(x, y, 1e-4), 0.01, 40);
    const double tiny_error = pose_distance(linear_step(tiny, SE2()), exact_minimum(tiny));
    EXPECT_LT(tiny_error, 1e-6) << "trial " << trial;
    // At 0.1 rad the small-angle approximation is visible: the error grows like theta^2.
    const PlanePairs large = random_plane_pairs(rng, SE2(x, y, 0.1), 0.01, 40);
    const double large_error = pose_distance(linear_step(large, SE2()), exact_minimum(large));
    EXPECT_GT(large_error, 1e-5) << "trial " << trial;
    EXPECT_LT(large_error, 0.1) << "trial " << trial;
  }
}

TEST(PointToPlaneStep, IteratingTheLinearStepConvergesToTheExactMinimiser) {
  Rng rng(3);
  for (const SE2& T_true : {SE2(0.2, -0.1, 0.1), SE2(-0.5, 0.3, -0.3), SE2(0.1, 0.4, 0.5)}) {
    const PlanePairs pairs = random_plane_pairs(rng, T_true, 0.02, 50);
    const SE2 exact = exact_minimum(pairs);
    SE2 T;
    double previous = pose_distance(T, exact);
    for (int k = 0; k < 12; ++k) {
      T = linear_step(pairs, T);
      const double error = pose_distance(T, exact);
      EXPECT_LE(error, previous + 1e-12) << "iteration " << k;  // no step moves away
      previous = error;
    }
    EXPECT_LT(previous, 1e-9) << T << " vs " << exact;
    EXPECT_TRUE(poses_near(exact, T_true, 0.02, 0.01));  // and the minimiser is near the truth
  }
}

TEST(PointToPlaneStep, UnconstrainedDirectionGetsNoMotionAndBadInputIsRejected) {
  // Lines all along x (a corridor): the pseudo-inverse leaves x at 0, y and the heading move.
  std::vector<Point2> targets, normals, sources;
  for (int i = 0; i < 10; ++i) {
    for (const double wall : {-1.0, 1.0}) {
      targets.emplace_back(i, wall);
      normals.emplace_back(0.0, 1.0);
      sources.emplace_back(i + 0.3, wall - 0.2);
    }
  }
  const std::optional<SE2> step = solve_point_to_plane(targets, normals, sources);
  ASSERT_TRUE(step.has_value());
  EXPECT_TRUE(poses_near(*step, SE2(0.0, 0.2, 0.0), 1e-9, 1e-9)) << *step;
  const std::vector<Point2> two(2, Point2(1.0, 0.0));
  EXPECT_FALSE(solve_point_to_plane(two, two, two).has_value());
  EXPECT_THROW(solve_point_to_plane(targets, two, sources), Error);
}

// ---------------------------------------------------------------------------------------------
// The matcher on simulated scans.

struct Case {
  const World* world;
  SE2 T_world_target;
  SE2 T_target_source;
  std::uint64_t seed;
};

std::vector<Case> recovery_cases() {
  const SE2 office = testing::ScanPairOptions{}.T_world_target;
  const SE2 room(0.5, -0.3, 0.2);
  return {{&testing::office_world(), office, SE2(0.15, -0.05, 0.05), 1},
          {&testing::office_world(), office, SE2(-0.2, 0.2, 0.2), 2},
          {&testing::office_world(), office, SE2(0.3, 0.1, -0.15), 3},
          {&testing::room_world(), room, SE2(0.2, 0.1, 0.1), 4},
          {&testing::room_world(), room, SE2(-0.15, 0.05, -0.06), 5},
          {&testing::room_world(), room, SE2(0.4, -0.2, 0.1), 6}};
}

testing::ScanPair make_pair(const Case& c) {
  return testing::make_scan_pair(
      *c.world, {.T_world_target = c.T_world_target, .T_target_source = c.T_target_source, .beams = 720, .seed = c.seed});
}

// The plane through a target point is fitted to its 5 nearest neighbours, so the metric has no
// sampling bias (unlike point-to-point); what is left is the pull of the surfaces one scan sees
// and the other does not (the matcher has no rejection but the 0.3 m gate). Measured worst case
// over these pairs, forward and inverse: 6.4 mm and 1.6 mrad (with a 1 m gate: 24 mm, 9.5 mrad).
constexpr double kTranslationTolerance = 0.01;  // m
constexpr double kRotationTolerance = 0.003;    // rad

TEST(PointToPlane, RecoversKnownTransformsForwardAndInverse) {
  for (const Case& c : recovery_cases()) {
    const testing::ScanPair pair = make_pair(c);
    const MatchResult forward = match_point_to_plane(pair.target, pair.source, SE2());
    EXPECT_TRUE(forward.converged) << "seed " << c.seed;
    EXPECT_TRUE(poses_near(forward.T_target_source, pair.T_target_source, kTranslationTolerance, kRotationTolerance))
        << "seed " << c.seed;
    EXPECT_FALSE(forward.degenerate);
    EXPECT_GT(forward.inliers, pair.source.size() * 8 / 10);
    const MatchResult inverse = match_point_to_plane(pair.source, pair.target, SE2());
    EXPECT_TRUE(inverse.converged) << "seed " << c.seed;
    EXPECT_TRUE(poses_near(inverse.T_target_source, pair.T_target_source.inverse(), kTranslationTolerance,
                           kRotationTolerance))
        << "seed " << c.seed;
  }
}

TEST(PointToPlane, FillsTheWholeResult) {
  const testing::ScanPair pair = make_pair(recovery_cases()[3]);
  const MatchResult result = match_point_to_plane(pair.target, pair.source, SE2());
  EXPECT_TRUE(result.converged);
  EXPECT_GT(result.iterations, 1);
  EXPECT_LE(result.inliers, pair.source.size());
  EXPECT_GT(result.residual, 0.0);
  EXPECT_LT(result.residual, 0.03);  // point-to-line RMS, 1 cm range noise
  EXPECT_TRUE(is_valid_covariance(result.covariance));
  EXPECT_LT(result.covariance.diagonal().maxCoeff(), 1e-3);
  EXPECT_GT(result.covariance.diagonal().minCoeff(), 0.0);
}

TEST(PointToPlane, EstimatesTargetNormalsWhenTheTargetHasNone) {
  const testing::ScanPair pair = make_pair(recovery_cases()[0]);
  const PointToPlaneConfig config{.normal_neighbors = 7, .normal_max_distance = 0.3, .normal_min_neighbors = 4};
  // The same normals, estimated here with the matcher's settings: the same match, bit for bit.
  PointCloud2 with_normals = pair.target;
  estimate_normals(with_normals, {config.normal_neighbors, config.normal_max_distance, config.normal_min_neighbors});
  const MatchResult estimated = match_point_to_plane(pair.target, pair.source, SE2(), config);
  const MatchResult given = match_point_to_plane(with_normals, pair.source, SE2(), config);
  EXPECT_EQ(estimated.T_target_source, given.T_target_source);
  EXPECT_EQ(estimated.iterations, given.iterations);
  EXPECT_EQ(estimated.inliers, given.inliers);
  EXPECT_TRUE(poses_near(estimated.T_target_source, pair.T_target_source, kTranslationTolerance, kRotationTolerance));
  // Normals the target carries are used as they are: turned by 90 degrees they lie along the
  // walls, and the match goes wrong.
  PointCloud2 turned = with_normals;
  for (Point2& n : turned.normals) n = Point2(-n.y(), n.x());
  const MatchResult wrong = match_point_to_plane(turned, pair.source, SE2(), config);
  EXPECT_FALSE(poses_near(wrong.T_target_source, pair.T_target_source, kTranslationTolerance, kRotationTolerance));
  // Normals, but not one per point: an error, not a guess.
  PointCloud2 short_normals = with_normals;
  short_normals.normals.pop_back();
  EXPECT_THROW(match_point_to_plane(short_normals, pair.source, SE2(), config), Error);
}

TEST(PointToPlane, CorridorIsFlaggedDegenerateAlongItsAxis) {
  const testing::ScanPair pair = testing::make_scan_pair(
      testing::corridor_world(), {.T_world_target = SE2(0.0, 0.0, 0.0), .T_target_source = SE2(0.2, 0.05, 0.03)});
  const MatchResult result = match_point_to_plane(pair.target, pair.source, SE2());
  EXPECT_TRUE(result.degenerate);
  EXPECT_GT(std::abs(result.weak_direction.x()), 0.9) << result.weak_direction.transpose();
  // Across the corridor and in heading the walls still fix the pose; along it the pseudo-inverse
  // gives no motion, so x stays at the guess.
  EXPECT_NEAR(result.T_target_source.y(), 0.05, 0.01);
  EXPECT_NEAR(result.T_target_source.theta(), 0.03, 0.003);
  EXPECT_NEAR(result.T_target_source.x(), 0.0, 0.05);
  // The covariance says so: far larger along the axis than across it (apply() in degeneracy.hpp
  // gives the weak direction at least the information's eigenvalue ratio; measured 71x).
  EXPECT_GT(result.covariance(0, 0), 20.0 * result.covariance(1, 1));
}

TEST(PointToPlane, EmptyTinyOrFarApartCloudsDoNotConverge) {
  const testing::ScanPair pair = make_pair(recovery_cases()[3]);
  const SE2 guess(0.1, 0.2, 0.3);
  PointCloud2 tiny;
  tiny.points = {{1.0, 0.0}, {0.0, 1.0}};
  for (const auto& [target, source] : {std::pair{PointCloud2{}, pair.source}, std::pair{pair.target, PointCloud2{}},
                                       std::pair{tiny, pair.source}, std::pair{pair.target, tiny}}) {
    const MatchResult result = match_point_to_plane(target, source, guess);
    EXPECT_FALSE(result.converged);
    EXPECT_EQ(result.T_target_source, guess);
    EXPECT_GE(result.covariance.diagonal().minCoeff(), 1e5);
    EXPECT_EQ(result.inliers, 0U);
  }
  const MatchResult apart = match_point_to_plane(pair.target, pair.source, SE2(100.0, 0.0, 0.0));
  EXPECT_FALSE(apart.converged);
  EXPECT_EQ(apart.inliers, 0U);
  EXPECT_GE(apart.covariance.diagonal().minCoeff(), 1e5);
  // Points all on one spot have no normals: no pairs, no success.
  PointCloud2 clump;
  clump.points.assign(20, Point2(2.0, 1.0));
  const MatchResult clumped = match_point_to_plane(clump, pair.source, SE2());
  EXPECT_FALSE(clumped.converged);
  EXPECT_GE(clumped.covariance.diagonal().minCoeff(), 1e5);
}

// An iteration that comes back to a pose of its last four has entered a cycle of its
// associations: the steps would never shrink below the stopping test, so it is over.
TEST(PoseCycle, AReturnWithinFourIterationsIsACycleAndSteadyProgressIsNot) {
  constexpr double kTolerance = 1e-4;
  PoseCycle two;
  EXPECT_FALSE(two.returned_to(SE2(1.0, 2.0, 0.1), kTolerance, kTolerance));
  EXPECT_FALSE(two.returned_to(SE2(1.007, 2.0, 0.1), kTolerance, kTolerance));
  EXPECT_TRUE(two.returned_to(SE2(1.0 + 1e-6, 2.0, 0.1), kTolerance, kTolerance));
  PoseCycle steady;  // 1 mm a step: slow, but going somewhere
  for (int k = 0; k < 20; ++k) EXPECT_FALSE(steady.returned_to(SE2(0.001 * k, 0.0, 0.0), kTolerance, kTolerance));
  PoseCycle five;  // longer than the longest cycle recognised
  for (int k = 0; k < 5; ++k) EXPECT_FALSE(five.returned_to(SE2(0.01 * k, 0.0, 0.0), kTolerance, kTolerance));
  EXPECT_FALSE(five.returned_to(SE2(0.0, 0.0, 0.0), kTolerance, kTolerance));
  PoseCycle turning;  // headings compared across +-pi
  EXPECT_FALSE(turning.returned_to(SE2(0.0, 0.0, std::numbers::pi - 1e-6), kTolerance, kTolerance));
  EXPECT_FALSE(turning.returned_to(SE2(0.0, 0.0, std::numbers::pi - 0.01), kTolerance, kTolerance));
  EXPECT_TRUE(turning.returned_to(SE2(0.0, 0.0, -std::numbers::pi + 1e-6), kTolerance, kTolerance));
}

// IDC, IMRP and the tangent search remember two poses: a return after three steps is progress to
// them, a cycle to the default of four.
TEST(PoseCycle, ThePeriodBoundsTheCyclesRecognised) {
  constexpr double kTolerance = 1e-4;
  const std::vector<SE2> three_cycle = {SE2(0.0, 0.0, 0.0), SE2(0.01, 0.0, 0.0), SE2(0.0, 0.01, 0.0), SE2(0.0, 0.0, 0.0)};
  PoseCycle period_two(2);
  PoseCycle period_four;
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_FALSE(period_two.returned_to(three_cycle[k], kTolerance, kTolerance));
    EXPECT_FALSE(period_four.returned_to(three_cycle[k], kTolerance, kTolerance));
  }
  EXPECT_FALSE(period_two.returned_to(three_cycle[3], kTolerance, kTolerance));
  EXPECT_TRUE(period_four.returned_to(three_cycle[3], kTolerance, kTolerance));
  PoseCycle alternating(2);  // two sets of pairs taking turns
  EXPECT_FALSE(alternating.returned_to(SE2(0.0, 0.0, 0.0), kTolerance, kTolerance));
  EXPECT_FALSE(alternating.returned_to(SE2(0.01, 0.0, 0.0), kTolerance, kTolerance));
  EXPECT_TRUE(alternating.returned_to(SE2(0.0, 0.0, 0.0), kTolerance, kTolerance));
  EXPECT_THROW(PoseCycle(0), Error);
  EXPECT_THROW(PoseCycle(5), Error);
}

TEST(PointToPlane, InvalidConfigsThrow) {
  const testing::ScanPair pair = make_pair(recovery_cases()[3]);
  const auto run = [&](const PointToPlaneConfig& config) {
    return match_point_to_plane(pair.target, pair.source, SE2(), config);
  };
  EXPECT_THROW(run({.max_iterations = 0}), Error);
  EXPECT_THROW(run({.max_correspondence_distance = 0.0}), Error);
  EXPECT_THROW(run({.max_correspondence_distance = -1.0}), Error);
  EXPECT_THROW(run({.min_correspondences = 2}), Error);
  EXPECT_THROW(run({.min_translation_step = -1e-3}), Error);
  EXPECT_THROW(run({.min_rotation_step = -1e-3}), Error);
  EXPECT_THROW(run({.normal_neighbors = 1}), Error);
  EXPECT_THROW(run({.normal_max_distance = 0.0}), Error);
  EXPECT_THROW(run({.normal_min_neighbors = 1}), Error);
  EXPECT_THROW(match_point_to_plane(PointCloud2{}, PointCloud2{}, SE2(), {.max_iterations = -1}), Error);
}

}  // namespace
}  // namespace slam2d
