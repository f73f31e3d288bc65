// SPDX-License-Identifier: BSD-3-Clause
// Boolean and soft-weighted ICP (src/slam2d/registration/weighted_icp.hpp).
#include "slam2d/registration/weighted_icp.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>
#include <numbers>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/registration/icp.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using testing::make_scan_pair;
using testing::ScanPairOptions;

// Point-to-point ICP on 1-degree scans is biased by the sampling (the points of one scan are not
// the points of the other): a few cm after a 0.3 m move. Point-to-line is not.
constexpr double kTranslationTolerance = 0.04;  // m, point-to-point
constexpr double kAngleTolerance = 0.02;        // rad, point-to-point
constexpr double kLineTranslationTolerance = 0.01;  // m, point-to-line
constexpr double kLineAngleTolerance = 0.005;       // rad, point-to-line

// Office poses with structure in every direction: room S1 and room N3 (the fixture's default pose
// in the long south corridor leaves point-to-point ICP 10-16 cm off along the corridor).
const SE2 kOfficeRoomS1(7.0, 2.5, 0.3);
const SE2 kOfficeRoomN3(17.0, 16.0, -1.0);

double translation_error(const SE2& a, const SE2& b) { return (a.translation() - b.translation()).norm(); }
double angle_error(const SE2& a, const SE2& b) { return std::abs(angle_difference(a.theta(), b.theta())); }

ScanPairOptions room_options(const SE2& T_target_source, std::uint64_t seed = 1) {
  return {.T_world_target = SE2(-0.5, 0.3, 0.2), .T_target_source = T_target_source, .seed = seed};
}

/// `count` uniform random points in front of the sensor, 0.3 - 8 m away: clutter no target point explains.
void add_outliers(PointCloud2& cloud, std::size_t count, std::uint64_t seed) {
  Rng rng(seed);
  for (std::size_t i = 0; i < count; ++i) {
    const double range = rng.uniform(0.3, 8.0);
    const double bearing = rng.uniform(-std::numbers::pi / 2, std::numbers::pi / 2);
    cloud.points.emplace_back(range * std::cos(bearing), range * std::sin(bearing));
  }
}

TEST(WeightedIcpWeights, HandComputedValues) {
  WeightedIcpConfig config{.weighting = IcpWeighting::kBoolean, .weight_distance = 0.5};
  EXPECT_EQ(pair_weight(0.0, config), 1.0);
  EXPECT_EQ(pair_weight(0.5, config), 1.0);
  EXPECT_EQ(pair_weight(0.51, config), 0.0);
  config.weighting = IcpWeighting::kSoft;
  config.soft_kernel = SoftWeightKernel::kLinear;
  EXPECT_DOUBLE_EQ(pair_weight(0.125, config), 0.75);
  EXPECT_EQ(pair_weight(0.7, config), 0.0);
  config.soft_kernel = SoftWeightKernel::kGaussian;
  EXPECT_DOUBLE_EQ(pair_weight(0.5, config), std::exp(-0.5));
  config.soft_kernel = SoftWeightKernel::kCauchy;
  EXPECT_DOUBLE_EQ(pair_weight(1.0, config), 0.2);
}

struct RecoveryCase {
  const char* name;
  IcpWeighting weighting;
  ErrorMetric metric;
};

class WeightedIcpRecovery : public ::testing::TestWithParam<RecoveryCase> {
 protected:
  WeightedIcpConfig config() const { return {.weighting = GetParam().weighting, .metric = GetParam().metric}; }
  bool line() const { return GetParam().metric == ErrorMetric::kPointToLine; }
  ::testing::AssertionResult near(const SE2& actual, const SE2& expected) const {
    return test::poses_near(actual, expected, line() ? kLineTranslationTolerance : kTranslationTolerance,
                            line() ? kLineAngleTolerance : kAngleTolerance);
  }
};

TEST_P(WeightedIcpRecovery, OfficeForwardAndInverse) {
  const std::vector<SE2> truths = {SE2(0.15, -0.05, 0.05), SE2(-0.2, 0.1, -0.08), SE2(0.3, 0.0, 0.12)};
  for (const SE2& room : {kOfficeRoomS1, kOfficeRoomN3}) {
    for (std::size_t k = 0; k < truths.size(); ++k) {
      const auto pair =
          make_scan_pair(testing::office_world(), {.T_world_target = room, .T_target_source = truths[k], .seed = 10 + k});
      const MatchResult forward = match_weighted_icp(pair.target, pair.source, SE2(), config());
      EXPECT_TRUE(forward.converged);
      EXPECT_TRUE(near(forward.T_target_source, truths[k])) << room;
      const MatchResult inverse = match_weighted_icp(pair.source, pair.target, SE2(), config());
      EXPECT_TRUE(inverse.converged);
      EXPECT_TRUE(near(inverse.T_target_source, truths[k].inverse())) << room;
    }
  }
}

TEST_P(WeightedIcpRecovery, RoomFromPerturbedGuesses) {
  const SE2 truth(0.25, -0.1, 0.1);
  const auto pair = make_scan_pair(testing::room_world(), room_options(truth, 4));
  for (const SE2& error : {SE2(0.1, 0.1, 0.05), SE2(-0.15, 0.05, -0.1), SE2(0.0, -0.2, 0.0)}) {
    const SE2 guess = truth * error;
    const MatchResult forward = match_weighted_icp(pair.target, pair.source, guess, config());
    EXPECT_TRUE(forward.converged);
    EXPECT_TRUE(near(forward.T_target_source, truth)) << "guess " << guess;
    const MatchResult inverse = match_weighted_icp(pair.source, pair.target, guess.inverse(), config());
    EXPECT_TRUE(inverse.converged);
    EXPECT_TRUE(near(inverse.T_target_source, truth.inverse())) << "guess " << guess.inverse();
  }
}

TEST_P(WeightedIcpRecovery, FillsTheWholeResult) {
  const SE2 truth(0.15, -0.05, 0.05);
  const auto pair = make_scan_pair(testing::room_world(), room_options(truth));
  const MatchResult r = match_weighted_icp(pair.target, pair.source, SE2(), config());
  ASSERT_TRUE(r.converged);
  EXPECT_GT(r.iterations, 1);
  EXPECT_GT(r.inliers, pair.source.size() / 2);
  EXPECT_LE(r.inliers, pair.source.size());
  EXPECT_GT(r.residual, 0.0);
  EXPECT_LT(r.residual, 0.05);  // range noise is 1 cm
  EXPECT_FALSE(r.degenerate);
  // Censi's covariance from 1 cm range noise: small, positive definite, far below the "unknown" 1e6.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(r.covariance);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
  EXPECT_LT(eigen.eigenvalues().maxCoeff(), 1e-3);
}

INSTANTIATE_TEST_SUITE_P(
    Variants, WeightedIcpRecovery,
    ::testing::Values(RecoveryCase{"BooleanPointToPoint", IcpWeighting::kBoolean, ErrorMetric::kPointToPoint},
                      RecoveryCase{"SoftPointToPoint", IcpWeighting::kSoft, ErrorMetric::kPointToPoint},
                      RecoveryCase{"BooleanPointToLine", IcpWeighting::kBoolean, ErrorMetric::kPointToLine},
                      RecoveryCase{"SoftPointToLine", IcpWeighting::kSoft, ErrorMetric::kPointToLine}),
    [](const ::testing::TestParamInfo<RecoveryCase>& info) { return std::string(info.param.name); });

TEST(WeightedIcp, BooleanAndSoftSurviveTwentyPercentOutliers) {
  const SE2 truth(0.2, -0.08, 0.07);
  double boolean_total = 0.0, soft_total = 0.0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    auto pair = make_scan_pair(testing::office_world(), {.T_world_target = kOfficeRoomS1, .T_target_source = truth, .seed = seed});
    add_outliers(pair.source, pair.source.size() / 5, 100 + seed);
    const MatchResult boolean = match_boolean_icp(pair.target, pair.source, SE2());
    const MatchResult soft = match_soft_icp(pair.target, pair.source, SE2());
    EXPECT_TRUE(test::poses_near(boolean.T_target_source, truth, kTranslationTolerance, kAngleTolerance))
        << "seed " << seed << ": " << boolean.T_target_source;
    EXPECT_TRUE(test::poses_near(soft.T_target_source, truth, kTranslationTolerance, kAngleTolerance))
        << "seed " << seed << ": " << soft.T_target_source;
    boolean_total += translation_error(boolean.T_target_source, truth) + angle_error(boolean.T_target_source, truth);
    soft_total += translation_error(soft.T_target_source, truth) + angle_error(soft.T_target_source, truth);
  }
  EXPECT_LE(soft_total, boolean_total) << "soft " << soft_total << " vs Boolean " << boolean_total;
}

TEST(WeightedIcp, BooleanFunctionForcesItsWeighting) {
  // The same config through the two entry points: only the weighting differs.
  auto pair = make_scan_pair(testing::office_world(), {.seed = 7});
  add_outliers(pair.source, pair.source.size() / 5, 77);
  const WeightedIcpConfig soft_config{.weighting = IcpWeighting::kSoft};
  const MatchResult as_boolean = match_boolean_icp(pair.target, pair.source, SE2(), soft_config);
  const MatchResult boolean = match_weighted_icp(pair.target, pair.source, SE2(), {.weighting = IcpWeighting::kBoolean});
  const MatchResult soft = match_weighted_icp(pair.target, pair.source, SE2(), soft_config);
  EXPECT_EQ(as_boolean.T_target_source, boolean.T_target_source);
  EXPECT_EQ(match_soft_icp(pair.target, pair.source, SE2()).T_target_source, soft.T_target_source);
  EXPECT_FALSE(boolean.T_target_source == soft.T_target_source);
}

TEST(WeightedIcp, RejectionOptionsAndSubsamplingStillRecover) {
  const SE2 truth(0.15, -0.05, 0.05);
  auto pair = make_scan_pair(testing::office_world(), {.T_world_target = kOfficeRoomS1, .T_target_source = truth, .seed = 2});
  add_outliers(pair.source, pair.source.size() / 5, 9);
  const std::vector<WeightedIcpConfig> configs = {
      {.select_every = 2},
      {.reject_sigma_factor = 2.0},
      {.max_normal_angle = 0.5},
      {.weighting = IcpWeighting::kSoft, .weight_distance = 0.1, .soft_kernel = SoftWeightKernel::kCauchy},
      {.weighting = IcpWeighting::kSoft, .weight_distance = 0.2, .soft_kernel = SoftWeightKernel::kGaussian},
  };
  for (std::size_t k = 0; k < configs.size(); ++k) {
    const MatchResult r = match_weighted_icp(pair.target, pair.source, SE2(), configs[k]);
    EXPECT_TRUE(r.converged) << "config " << k;
    EXPECT_TRUE(test::poses_near(r.T_target_source, truth, kTranslationTolerance, kAngleTolerance))
        << "config " << k << ": " << r.T_target_source;
  }
  // The sigma rule and the normal test drop pairs the plain distance test keeps.
  const MatchResult plain = match_boolean_icp(pair.target, pair.source, SE2());
  EXPECT_LT(match_boolean_icp(pair.target, pair.source, SE2(), configs[1]).inliers, plain.inliers);
  EXPECT_LT(match_boolean_icp(pair.target, pair.source, SE2(), configs[2]).inliers, plain.inliers);
}

TEST(WeightedIcp, BooleanWithoutAThresholdIsBeslMcKayIcp) {
  // With the Boolean threshold at the rejection distance every kept pair has weight 1: the same
  // pairs and the same closed form as point-to-point ICP, so the same estimate.
  const SE2 truth(0.2, -0.1, 0.08);
  const auto pair = make_scan_pair(testing::office_world(), {.T_target_source = truth, .seed = 6});
  const MatchResult boolean = match_boolean_icp(
      pair.target, pair.source, SE2(), {.weight_distance = 1.0, .translation_tolerance = 1e-7, .rotation_tolerance = 1e-7});
  const MatchResult icp = match_icp(pair.target, pair.source, SE2(),
                                    {.min_mse_change = 0.0, .min_translation_step = 1e-7, .min_rotation_step = 1e-7});
  EXPECT_TRUE(test::poses_near(boolean.T_target_source, icp.T_target_source, 1e-5, 1e-5))
      << boolean.T_target_source << " vs " << icp.T_target_source;
  EXPECT_EQ(boolean.inliers, icp.inliers);
}

TEST(WeightedIcp, CorridorIsDegenerate) {
  const auto pair =
      make_scan_pair(testing::corridor_world(), {.T_world_target = SE2(0.0, 0.0, 0.0), .T_target_source = SE2(0.1, 0.02, 0.02)});
  for (const auto metric : {ErrorMetric::kPointToPoint, ErrorMetric::kPointToLine}) {
    const MatchResult r = match_boolean_icp(pair.target, pair.source, SE2(0.1, 0.0, 0.0), {.metric = metric});
    EXPECT_TRUE(r.degenerate);
    EXPECT_GT(std::abs(r.weak_direction.x()), 0.99) << r.weak_direction.transpose();  // along the corridor
    // Across it the walls pin the pose down.
    EXPECT_NEAR(r.T_target_source.y(), 0.02, 0.01);
    EXPECT_NEAR(r.T_target_source.theta(), 0.02, 0.005);
  }
}

TEST(WeightedIcp, EmptyAndTinyCloudsFail) {
  const auto pair = make_scan_pair(testing::office_world());
  const SE2 guess(0.1, 0.2, 0.3);
  PointCloud2 tiny;
  tiny.points = {Point2(1, 0), Point2(0, 1)};
  for (const auto& [target, source] : {std::pair{PointCloud2{}, pair.source}, std::pair{pair.target, PointCloud2{}},
                                       std::pair{tiny, pair.source}, std::pair{pair.target, tiny}}) {
    for (const auto weighting : {IcpWeighting::kBoolean, IcpWeighting::kSoft}) {
      const MatchResult r = match_weighted_icp(target, source, guess, {.weighting = weighting});
      EXPECT_FALSE(r.converged);
      EXPECT_GE(r.covariance.diagonal().minCoeff(), 1e6);
      EXPECT_EQ(r.T_target_source, guess);
    }
  }
}

TEST(WeightedIcp, NoOverlapFailsInsteadOfReturningTheGuess) {
  // The source 50 m away from every target point: no pair within reach.
  const auto pair = make_scan_pair(testing::office_world());
  const MatchResult r = match_boolean_icp(pair.target, pair.source, SE2(50.0, 0.0, 0.0));
  EXPECT_FALSE(r.converged);
  EXPECT_GE(r.covariance.diagonal().minCoeff(), 1e6);
}

TEST(WeightedIcp, InvalidConfigsThrow) {
  const auto pair = make_scan_pair(testing::office_world());
  const std::vector<WeightedIcpConfig> invalid = {
      {.select_every = 0},
      {.weight_distance = 0.0},
      {.weight_distance = std::nan("")},
      {.max_correspondence_distance = -1.0},
      {.reject_sigma_factor = -0.5},
      {.max_normal_angle = 4.0},
      {.normal_neighbors = 2},
      {.normal_max_distance = 0.0},
      {.max_iterations = 0},
      {.translation_tolerance = -1e-3},
      {.rotation_tolerance = std::numeric_limits<double>::infinity()},
      {.min_correspondences = 2},
      {.range_sigma = 0.0},
  };
  for (std::size_t k = 0; k < invalid.size(); ++k) {
    EXPECT_THROW(validate(invalid[k]), Error) << "config " << k;
    EXPECT_THROW(match_boolean_icp(pair.target, pair.source, SE2(), invalid[k]), Error) << "config " << k;
    EXPECT_THROW(match_soft_icp(PointCloud2{}, PointCloud2{}, SE2(), invalid[k]), Error) << "config " << k;
  }
  EXPECT_NO_THROW(validate(WeightedIcpConfig{}));
}

}  // namespace
}  // namespace slam2d
