// SPDX-License-Identifier: BSD-3-Clause
// GA + ICP hybrid (Martinez et al. 2006, src/slam2d/registration/ga_icp.hpp).
#include "slam2d/registration/ga_icp.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/icp.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using testing::make_scan_pair;

// The refinement is point-to-point ICP, biased by the 1-degree sampling by a few cm (see
// weighted_icp_test.cpp); the poses are in rooms constrained in every direction.
constexpr double kTranslationTolerance = 0.05;  // m
constexpr double kAngleTolerance = 0.02;        // rad
const SE2 kOfficeRoomS1(7.0, 2.5, 0.3);

/// Points at `range` on the bearings first, first + step, ... (beam order).
PointCloud2 arc(double range, double first, double step, int count) {
  PointCloud2 cloud;
  for (int i = 0; i < count; ++i) {
    const double a = first + step * i;
    cloud.points.emplace_back(range * std::cos(a), range * std::sin(a));
  }
  return cloud;
}

/// A wide search window, large enough for the large-offset tests.
GaIcpConfig wide_window(std::uint64_t seed = 1) {
  return {.window_x = 1.0, .window_y = 1.0, .window_theta = 0.8, .population = 60, .generations = 40, .seed = seed};
}

TEST(GaIcpChromosome, DecodesHandComputedOffsets) {
  const GaIcpConfig config{.window_x = 1.0, .window_y = 2.0, .window_theta = 0.3, .bits_per_gene = 2};
  // x = 3 (bits 0-1), y = 0 (bits 2-3), theta = 1 (bits 4-5): 0b01'00'11.
  const Eigen::Vector3d offset = decode_chromosome(0b010011, config);
  EXPECT_DOUBLE_EQ(offset.x(), 1.0);
  EXPECT_DOUBLE_EQ(offset.y(), -2.0);
  EXPECT_DOUBLE_EQ(offset.z(), -0.3 + 0.6 / 3.0);
  EXPECT_TRUE(decode_chromosome(0, config).isApprox(Eigen::Vector3d(-1.0, -2.0, -0.3)));
}

TEST(GaIcpRangeDifference, HandComputedErrors) {
  // The source sees an arc at 2 m on 5 beams 0.1 rad apart (the middle one dropped): 4 readings.
  PointCloud2 source = arc(2.0, -0.2, 0.1, 5);
  source.points.erase(source.points.begin() + 2);
  const RangeDifferenceMetric metric(source, {.max_range_difference = 0.5, .min_matching_index = 0.5});
  EXPECT_EQ(metric.beams(), 5u);
  EXPECT_NEAR(metric.angular_resolution(), 0.1, 1e-12);
  // The same target at 2.1 m: every reading matches, 0.1 m off: I = 1, e = 0.01.
  const RangeDifferenceScore same = metric.score(arc(2.1, -0.2, 0.1, 5), SE2());
  EXPECT_EQ(same.matched_readings, 4u);
  EXPECT_DOUBLE_EQ(same.matching_index, 1.0);
  EXPECT_NEAR(same.matched_rms, 0.1, 1e-12);
  EXPECT_NEAR(same.error, 0.01, 1e-12);
  // Seen from a source pose 0.3 m ahead: ranges shrink; on the central beams by ~0.3.
  const PointCloud2 ahead = arc(2.0, -0.2, 0.1, 5);
  const SE2 T(0.3, 0.0, 0.0);
  double expected = 0.0;
  for (const Point2& q : ahead.points) {
    const Point2 p = q - Point2(0.3, 0.0);
    const double bearing = std::atan2(p.y(), p.x());
    const long beam = std::lround((bearing + 0.2) / 0.1);
    if (beam == 2 || beam < 0 || beam > 4) continue;
    expected += std::pow(2.0 - p.norm(), 2);  // all within E_max = 0.5
  }
  const RangeDifferenceScore moved = metric.score(ahead, T);
  EXPECT_EQ(moved.matched_readings, 4u);  // points move outward in bearing but stay within 5 beams
  EXPECT_NEAR(moved.error, expected / 4.0, 1e-12);
  // A 1 m difference does not match: I = 0, infeasible.
  const RangeDifferenceScore far = metric.score(arc(3.0, -0.2, 0.1, 5), SE2());
  EXPECT_EQ(far.matched_readings, 0u);
  EXPECT_EQ(far.error, std::numeric_limits<double>::infinity());
  // Matching index: a target covering 2 of the 4 readings, exactly: I = 0.5, e = 0.5 * 0 + 0.5 * 0.25.
  const RangeDifferenceScore half = metric.score(arc(2.0, -0.2, 0.1, 2), SE2());
  EXPECT_DOUBLE_EQ(half.matching_index, 0.5);
  EXPECT_NEAR(half.error, 0.125, 1e-12);
  // ... so the pose explaining every reading 0.1 m off beats the one explaining half of them
  // exactly (a mean over the overlapping beams alone, 0 against 0.01, would pick the latter).
  EXPECT_LT(same.error, half.error);
  // Half a reading's worth more matched (3 of 4, one 0.4 m off, one beyond E_max): I = 0.75.
  PointCloud2 mixed = arc(2.0, -0.2, 0.1, 5);
  mixed.points[3] *= 2.4 / 2.0;
  mixed.points[4] *= 2.6 / 2.0;
  const RangeDifferenceScore partial = metric.score(mixed, SE2());
  EXPECT_EQ(partial.matched_readings, 3u);
  EXPECT_NEAR(partial.error, 0.75 * (0.16 / 3.0) + 0.25 * 0.25, 1e-12);
  EXPECT_NEAR(partial.matched_rms, std::sqrt(0.16 / 3.0), 1e-12);
  // One of 4 is below the feasibility bound.
  EXPECT_EQ(metric.score(arc(2.0, -0.2, 0.1, 1), SE2()).error, std::numeric_limits<double>::infinity());
  // Nothing in the field of view.
  EXPECT_EQ(metric.score(arc(2.0, 2.0, 0.1, 5), SE2()).matched_readings, 0u);
}

TEST(GaIcpRangeDifference, MinimalAtTheTruthOnSimulatedScans) {
  const auto pair = make_scan_pair(testing::office_world());
  const RangeDifferenceMetric metric(pair.source, {});
  EXPECT_NEAR(metric.angular_resolution(), pair.source_scan.angle_increment, 1e-9);
  const RangeDifferenceScore truth = metric.score(pair.target, pair.T_target_source);
  EXPECT_GT(truth.matching_index, 0.9);  // the rest: what the target does not see
  EXPECT_LT(truth.matched_rms, 0.05);
  const double at_truth = truth.error;
  EXPECT_LT(at_truth, 0.25 * (1.0 - truth.matching_index) + 0.0025);
  for (const SE2& error : {SE2(0.1, 0, 0), SE2(0, 0.1, 0), SE2(0, 0, 0.05), SE2(-0.2, 0.1, -0.1)}) {
    EXPECT_GT(metric.score(pair.target, pair.T_target_source * error).error, at_truth) << error;
  }
}

TEST(GaIcp, RecoversALargeOffsetWherePlainIcpFails) {
  const Eigen::Vector3d offset(0.8, 0.6, 0.6);  // m, m, rad: inside the wide window
  for (const auto& [world, options] :
       {std::pair{&testing::office_world(),
                  testing::ScanPairOptions{.T_world_target = kOfficeRoomS1, .T_target_source = SE2(0.15, -0.05, 0.05)}},
        std::pair{&testing::room_world(),
                  testing::ScanPairOptions{.T_world_target = SE2(-0.5, 0.3, 0.2), .T_target_source = SE2(0.2, 0.1, -0.1)}}}) {
    const auto pair = make_scan_pair(*world, options);
    const SE2& truth = pair.T_target_source;
    const MatchResult forward = match_ga_icp(pair.target, pair.source, SE2::from_vector(truth.vector() + offset), wide_window());
    EXPECT_TRUE(forward.converged);
    EXPECT_TRUE(test::poses_near(forward.T_target_source, truth, kTranslationTolerance, kAngleTolerance))
        << world->name << ": " << forward.T_target_source << " vs " << truth;
    // Inverse: the source as the target, the opposite offset on the inverse pose. Plain ICP from
    // there falls into another minimum.
    const SE2 inverse_truth = truth.inverse();
    const SE2 inverse_guess = SE2::from_vector(inverse_truth.vector() - offset);
    const MatchResult icp = match_icp(pair.source, pair.target, inverse_guess);
    EXPECT_FALSE(test::poses_near(icp.T_target_source, inverse_truth, 0.2, 0.1))
        << world->name << ": plain ICP found it: " << icp.T_target_source;
    const MatchResult inverse = match_ga_icp(pair.source, pair.target, inverse_guess, wide_window());
    EXPECT_TRUE(inverse.converged);
    EXPECT_TRUE(test::poses_near(inverse.T_target_source, inverse_truth, kTranslationTolerance, kAngleTolerance))
        << world->name << ": " << inverse.T_target_source << " vs " << inverse_truth;
  }
}

// Something the source sees and the target does not (a person who walked in): on `beams`
// consecutive beams from `first`, the source's readings `nearer` metres short of the wall.
PointCloud2 with_object(PointCloud2 source, std::size_t first, std::size_t beams, double nearer) {
  for (std::size_t i = first; i < first + beams && i < source.size(); ++i) {
    Point2& p = source.points[i];
    p *= (p.norm() - nearer) / p.norm();
  }
  return source;
}

TEST(GaIcp, TheReducedGateKeepsWhatOnlyOneScanSeesOutOfIcp) {
  const GaIcpConfig reduced{};
  GaIcpConfig fixed = reduced;
  fixed.icp_gate_factor = 0.0;  // ICP alone's 1 m gate after the GA
  int reduced_better = 0;
  for (const auto& [world, options] :
       {std::pair{&testing::office_world(),
                  testing::ScanPairOptions{.T_world_target = kOfficeRoomS1, .T_target_source = SE2(0.15, -0.05, 0.05)}},
        std::pair{&testing::room_world(),
                  testing::ScanPairOptions{.T_world_target = SE2(-0.5, 0.3, 0.2), .T_target_source = SE2(0.2, 0.1, -0.1)}}}) {
    const auto pair = make_scan_pair(*world, options);
    const SE2& truth = pair.T_target_source;
    for (const std::size_t first : {30u, 80u, 120u}) {
      const PointCloud2 source = with_object(pair.source, first, 20, 0.7);
      const SE2 guess = truth * SE2(0.1, -0.1, 0.05);
      const GaSearchResult search = ga_search(pair.target, source, guess, reduced);
      const double gate = icp_gate(search, reduced);
      EXPECT_LT(gate, 0.5) << world->name << " beam " << first;
      EXPECT_GE(gate, reduced.icp_min_correspondence_distance);
      const MatchResult with_reduced = match_ga_icp(pair.target, source, guess, reduced);
      const MatchResult with_fixed = match_ga_icp(pair.target, source, guess, fixed);
      const auto error = [&](const MatchResult& r) { return (truth.inverse() * r.T_target_source).translation().norm(); };
      EXPECT_TRUE(test::poses_near(with_reduced.T_target_source, truth, kTranslationTolerance, kAngleTolerance))
          << world->name << " beam " << first << ": " << with_reduced.T_target_source << " vs " << truth;
      std::cout << world->name << " beam " << first << ": gate " << gate << " m, error " << error(with_reduced)
                << " m reduced, " << error(with_fixed) << " m with the 1 m gate\n";
      if (error(with_reduced) + 0.01 < error(with_fixed)) ++reduced_better;
    }
  }
  EXPECT_GE(reduced_better, 4);  // the 1 m gate lets the object pull ICP off, by more than 1 cm
}

TEST(GaIcp, FillsTheWholeResult) {
  const auto pair = make_scan_pair(testing::office_world(), {.T_world_target = kOfficeRoomS1});
  const GaIcpConfig config{};
  const MatchResult r = match_ga_icp(pair.target, pair.source, SE2(), config);
  ASSERT_TRUE(r.converged);
  EXPECT_TRUE(test::poses_near(r.T_target_source, pair.T_target_source, kTranslationTolerance, kAngleTolerance));
  EXPECT_GT(r.iterations, config.generations);  // generations + ICP iterations
  EXPECT_GT(r.inliers, pair.source.size() / 2);
  EXPECT_GT(r.residual, 0.0);
  EXPECT_LT(r.residual, 0.05);
  EXPECT_FALSE(r.degenerate);
  EXPECT_GT(r.covariance.diagonal().minCoeff(), 0.0);
  EXPECT_LT(r.covariance.diagonal().maxCoeff(), 1e-3);
  // The GA stage alone lands inside ICP's basin, within a few grid steps of the truth.
  const GaSearchResult search = ga_search(pair.target, pair.source, SE2(), config);
  EXPECT_TRUE(test::poses_near(search.T_target_source, pair.T_target_source, 0.1, 0.05)) << search.T_target_source;
  EXPECT_EQ(search.generations, config.generations);
  EXPECT_GT(search.evaluations, static_cast<std::size_t>(config.population));
}

TEST(GaIcp, SameSeedSameResultOtherSeedsStillCorrect) {
  const auto pair = make_scan_pair(testing::office_world(),
                                   {.T_world_target = kOfficeRoomS1, .T_target_source = SE2(0.3, 0.2, -0.2), .seed = 3});
  const SE2 guess(0.0, 0.0, 0.2);
  const MatchResult a = match_ga_icp(pair.target, pair.source, guess, wide_window(11));
  const MatchResult b = match_ga_icp(pair.target, pair.source, guess, wide_window(11));
  EXPECT_EQ(a.T_target_source, b.T_target_source);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.covariance, b.covariance);
  const GaSearchResult search_a = ga_search(pair.target, pair.source, guess, wide_window(11));
  const GaSearchResult search_b = ga_search(pair.target, pair.source, guess, wide_window(11));
  EXPECT_EQ(search_a.T_target_source, search_b.T_target_source);
  EXPECT_EQ(search_a.evaluations, search_b.evaluations);
  const GaSearchResult search_c = ga_search(pair.target, pair.source, guess, wide_window(12));
  EXPECT_FALSE(search_a.T_target_source == search_c.T_target_source);  // another stream, another grid point
  for (const std::uint64_t seed : {12u, 13u, 14u}) {
    const MatchResult r = match_ga_icp(pair.target, pair.source, guess, wide_window(seed));
    EXPECT_TRUE(test::poses_near(r.T_target_source, pair.T_target_source, kTranslationTolerance, kAngleTolerance))
        << "seed " << seed << ": " << r.T_target_source;
  }
}

TEST(GaIcp, EmptyAndTinyCloudsFail) {
  const auto pair = make_scan_pair(testing::office_world());
  const SE2 guess(0.1, 0.2, 0.3);
  PointCloud2 tiny;
  tiny.points = {Point2(1, 0), Point2(0, 1)};
  for (const auto& [target, source] : {std::pair{PointCloud2{}, pair.source}, std::pair{pair.target, PointCloud2{}},
                                       std::pair{tiny, pair.source}, std::pair{pair.target, tiny}}) {
    const MatchResult r = match_ga_icp(target, source, guess);
    EXPECT_FALSE(r.converged);
    EXPECT_GE(r.covariance.diagonal().minCoeff(), 1e6);
    EXPECT_EQ(r.T_target_source, guess);
    EXPECT_EQ(ga_search(target, source, guess).T_target_source, guess);
  }
}

TEST(GaIcp, InvalidConfigsThrow) {
  const auto pair = make_scan_pair(testing::office_world());
  const std::vector<GaIcpConfig> invalid = {
      {.window_x = 0.0},
      {.window_y = -1.0},
      {.window_theta = 4.0},
      {.bits_per_gene = 1},
      {.bits_per_gene = 21},
      {.population = 1},
      {.generations = 0},
      {.crossover_rate = 1.5},
      {.mutation_rate = -0.1},
      {.elite = 40},
      {.tournament_size = 0},
      {.max_range_difference = 0.0},
      {.min_matching_index = 1.1},
      {.icp_gate_factor = -1.0},
      {.icp_min_correspondence_distance = 0.0},
      {.angular_resolution = -0.01},
      {.icp_max_iterations = 0},
      {.icp_max_correspondence_distance = std::numeric_limits<double>::quiet_NaN()},
      {.icp_min_correspondences = 2},
  };
  for (std::size_t k = 0; k < invalid.size(); ++k) {
    EXPECT_THROW(validate(invalid[k]), Error) << "config " << k;
    EXPECT_THROW(match_ga_icp(pair.target, pair.source, SE2(), invalid[k]), Error) << "config " << k;
    EXPECT_THROW(match_ga_icp(PointCloud2{}, PointCloud2{}, SE2(), invalid[k]), Error) << "config " << k;
  }
  EXPECT_NO_THROW(validate(GaIcpConfig{}));
}

}  // namespace
}  // namespace slam2d
