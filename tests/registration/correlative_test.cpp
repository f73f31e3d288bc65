// SPDX-License-Identifier: BSD-3-Clause
// Correlative scan matching (Olson 2009; src/slam2d/registration/correlative.*): the lookup table
// against hand-computed values and brute-force pooling, the fast searches against the exhaustive
// one, recovery of known transforms, covariance and degeneracy, errors.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/correlative.hpp"
#include "slam2d/registration/correlative_grid.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using testing::make_scan_pair;
using testing::ScanPairOptions;

constexpr double kDeg = std::numbers::pi / 180.0;

PointCloud2 cloud_of(std::vector<Point2> points) {
  PointCloud2 cloud;
  cloud.points = std::move(points);
  return cloud;
}

/// A configuration small enough for the exhaustive search to stay fast in tests.
CorrelativeConfig test_config(CorrelativeSearch search) {
  CorrelativeConfig config;
  config.resolution = 0.02;
  config.sigma = 0.03;
  config.window_x = 0.2;
  config.window_y = 0.2;
  config.window_theta = 0.08;
  config.angular_step = 0.25 * kDeg;
  config.search = search;
  return config;
}

/// The sensor of issue 3's speed target: 1080 beams over 270 deg (1 cm range noise).
ScanPairOptions issue_sensor() {
  ScanPairOptions options;
  options.beams = 1080;
  options.field_of_view = 270.0 * kDeg;
  return options;
}

// ---- The lookup table ------------------------------------------------------------------------

TEST(CorrelativeGrid, CellScoresAreTheTruncatedGaussianOfTheDistanceToTheNearestPoint) {
  const CorrelativeGridConfig config{.resolution = 0.01, .sigma = 0.02, .truncation = 2.0, .levels = 3};
  const PointCloud2 target = cloud_of({{0.0, 0.0}, {0.3, 0.1}});
  const CorrelativeGrid grid(target, config);
  const double d_max = 0.04;
  EXPECT_DOUBLE_EQ(grid.max_distance(), d_max);
  int positive = 0;
  for (int y = -5; y < grid.height() + 5; ++y) {
    for (int x = -5; x < grid.width() + 5; ++x) {
      const Eigen::Vector2d centre = grid.geometry().cell_center({x, y});
      double d2 = 1e9;
      for (const Point2& p : target.points) d2 = std::min(d2, (centre - p).squaredNorm());
      const int expected = d2 < d_max * d_max ? static_cast<int>(std::lround(255.0 * (1.0 - d2 / (d_max * d_max)))) : 0;
      ASSERT_EQ(grid.score(0, x, y), expected) << x << " " << y;
      positive += expected > 0;
    }
  }
  // Two discs of radius 4 cells: about 2 pi 4^2 cells score above 0.
  EXPECT_GT(positive, 80);
  EXPECT_LT(positive, 2 * 81);
  // A point's own cell: its centre lies at most half a diagonal (0.0071 m) away.
  const CellIndex own = grid.geometry().cell_of(target.points[0]);
  EXPECT_GE(grid.score(0, own.x, own.y), static_cast<int>(255 * (1.0 - 0.5 * 0.01 * 0.01 / (d_max * d_max))));
}

TEST(CorrelativeGrid, LogLikelihoodAndDistanceInvertTheScore) {
  const CorrelativeGrid grid(cloud_of({{1.0, 2.0}}), {.resolution = 0.05, .sigma = 0.1, .truncation = 3.0});
  EXPECT_DOUBLE_EQ(grid.log_likelihood(kMaxCellScore), 0.0);
  EXPECT_DOUBLE_EQ(grid.log_likelihood(0), -4.5);  // -d_max^2 / (2 sigma^2) = -3^2 / 2
  // Eq. (1): log p = -d^2 / (2 sigma^2) at the distance a score stands for.
  for (int s : {1, 60, 128, 254}) {
    const double d = grid.distance_of_score(s);
    EXPECT_NEAR(grid.log_likelihood(s), -d * d / (2 * 0.1 * 0.1), 1e-12) << s;
  }
  EXPECT_DOUBLE_EQ(grid.distance_of_score(kMaxCellScore), 0.0);
  EXPECT_DOUBLE_EQ(grid.distance_of_score(0), 0.3);
}

TEST(CorrelativeGrid, SegmentsScoreTheirWholeLength) {
  const PointCloud2 target = cloud_of({{0.0, 0.0}, {0.5, 0.0}});
  const CorrelativeGrid points(target, {.resolution = 0.01, .sigma = 0.01, .truncation = 3.0});
  const CorrelativeGrid segments(target, {.resolution = 0.01, .sigma = 0.01, .truncation = 3.0, .max_segment_length = 0.6});
  const CellIndex middle = points.geometry().cell_of({0.255, 0.0});
  EXPECT_EQ(points.score(0, middle.x, middle.y), 0);
  EXPECT_GT(segments.score(0, middle.x, middle.y), 200);  // the cell centre lies 5 mm off the segment
  const CorrelativeGrid too_short(target, {.resolution = 0.01, .sigma = 0.01, .truncation = 3.0, .max_segment_length = 0.4});
  EXPECT_EQ(too_short.score(0, middle.x, middle.y), 0);
}

TEST(CorrelativeGrid, PooledLevelsAreTheMaxOfTheLevelZeroWindowsAbove) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-0.4, 0.4);
  std::vector<Point2> points;
  for (int n = 0; n < 25; ++n) points.emplace_back(coordinate(rng), coordinate(rng));
  const CorrelativeGrid grid(cloud_of(points), {.resolution = 0.02, .sigma = 0.02, .truncation = 2.0, .levels = 5});
  ASSERT_EQ(grid.levels(), 5);
  ASSERT_EQ(grid.padding(), 15);
  const int lo = -grid.padding() - 3;
  for (int level = 1; level < grid.levels(); ++level) {
    const int side = 1 << level;
    for (int y = lo; y < grid.height() + grid.padding() + 3; ++y) {
      for (int x = lo; x < grid.width() + grid.padding() + 3; ++x) {
        int expected = 0;
        for (int v = y; v < y + side; ++v) {
          for (int u = x; u < x + side; ++u) expected = std::max(expected, grid.score(0, u, v));
        }
        ASSERT_EQ(grid.score(level, x, y), expected) << level << " " << x << " " << y;
      }
    }
  }
}

// A grid's rasters come from those this thread freed (correlative_grid.cpp): built after larger
// grids of other clouds were freed, a grid holds exactly the cells of the same grid built in a
// thread that never freed one (nothing left over from the rasters' earlier grids).
TEST(CorrelativeGrid, ReusedRastersHoldNothingOfTheirEarlierGrids) {
  std::mt19937 rng(11);
  const auto random_cloud = [&](double half_side, int points) {
    std::uniform_real_distribution<double> coordinate(-half_side, half_side);
    std::vector<Point2> out;
    for (int n = 0; n < points; ++n) out.emplace_back(coordinate(rng), coordinate(rng));
    return cloud_of(std::move(out));
  };
  const CorrelativeGridConfig config{.resolution = 0.02, .sigma = 0.03, .truncation = 2.0, .levels = 4};
  const PointCloud2 small = random_cloud(2.6, 40);  // rasters of about 80 KB, cached (64 KB and more)
  std::vector<std::vector<std::uint8_t>> expected;
  const auto cells_of = [&](const CorrelativeGrid& grid) {
    std::vector<std::vector<std::uint8_t>> levels;
    const auto size = static_cast<std::size_t>(grid.stride()) * static_cast<std::size_t>(grid.stored_rows());
    for (int level = 0; level < grid.levels(); ++level) {
      levels.emplace_back(grid.level_data(level), grid.level_data(level) + size);
    }
    return levels;
  };
  std::thread([&] { expected = cells_of(CorrelativeGrid(small, config)); }).join();
  ASSERT_EQ(expected.size(), 4u);
  for (int round = 0; round < 3; ++round) {
    {
      const CorrelativeGrid dense(random_cloud(3.0, 2000), config);  // its rasters freed full of scores
      ASSERT_GT(static_cast<std::size_t>(dense.stride()) * dense.stored_rows(), expected[0].size());
    }
    EXPECT_EQ(cells_of(CorrelativeGrid(small, config)), expected) << round;
  }
}

TEST(CorrelativeGrid, EmptyTargetScoresNothing) {
  const CorrelativeGrid grid(PointCloud2{});
  EXPECT_TRUE(grid.empty());
  EXPECT_EQ(grid.score(0, 0, 0), 0);
  EXPECT_TRUE(CorrelativeGrid().empty());
}

TEST(CorrelativeGrid, EstimatesTargetNormalsWhenAbsent) {
  std::vector<Point2> wall;
  for (int n = 0; n < 20; ++n) wall.emplace_back(-1.0 + 0.1 * n, 2.0);
  const CorrelativeGrid grid(cloud_of(wall));
  ASSERT_EQ(grid.target().normals.size(), wall.size());
  EXPECT_NEAR(std::abs(grid.target().normals[10].y()), 1.0, 1e-6);
}

TEST(CorrelativeGrid, InvalidConfigurationsThrow) {
  const PointCloud2 target = cloud_of({{0.0, 0.0}});
  EXPECT_THROW(CorrelativeGrid(target, {.resolution = 0.0}), Error);
  EXPECT_THROW(CorrelativeGrid(target, {.resolution = -0.01}), Error);
  EXPECT_THROW(CorrelativeGrid(target, {.sigma = 0.0}), Error);
  EXPECT_THROW(CorrelativeGrid(target, {.truncation = -1.0}), Error);
  EXPECT_THROW(CorrelativeGrid(target, {.max_segment_length = -0.1}), Error);
  EXPECT_THROW(CorrelativeGrid(target, {.levels = 0}), Error);
  EXPECT_THROW(CorrelativeGrid(target, {.levels = 17}), Error);
  EXPECT_THROW(CorrelativeGrid(cloud_of({{0.0, 0.0}, {1e6, 1e6}}), {.resolution = 0.001}), Error);  // too many cells
  EXPECT_THROW(CorrelativeGrid(cloud_of({{0.0, std::nan("")}})), Error);
}

// ---- The three searches agree ------------------------------------------------------------------

void expect_same_match(const MatchResult& a, const MatchResult& b) {
  EXPECT_TRUE(a.T_target_source == b.T_target_source) << a.T_target_source << " vs " << b.T_target_source;
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.residual, b.residual);
  EXPECT_EQ(a.converged, b.converged);
}

/// All three searches on one problem: the fast ones return the exhaustive argmax. Returns the
/// poses each scored (exhaustive, multi-resolution, branch-and-bound).
std::array<int, 3> expect_searches_agree(const CorrelativeGrid& grid, const PointCloud2& source, const SE2& guess,
                                         CorrelativeConfig config) {
  config.search = CorrelativeSearch::kExhaustive;
  const MatchResult exhaustive = match_correlative(grid, source, guess, config);
  config.search = CorrelativeSearch::kMultiResolution;
  const MatchResult multi = match_correlative(grid, source, guess, config);
  config.search = CorrelativeSearch::kBranchAndBound;
  const MatchResult bnb = match_correlative(grid, source, guess, config);
  SCOPED_TRACE(::testing::Message() << "guess " << guess << " window " << config.window_x << " " << config.window_y
                                    << " " << config.window_theta << " levels " << grid.levels());
  expect_same_match(multi, exhaustive);
  expect_same_match(bnb, exhaustive);
  return {exhaustive.iterations, multi.iterations, bnb.iterations};
}

/// The table for the fast searches: the levels branch-and-bound needs, unless set.
CorrelativeGrid grid_for(const PointCloud2& target, CorrelativeConfig config) {
  config.search = CorrelativeSearch::kBranchAndBound;
  return CorrelativeGrid(target, correlative_grid_config(config));
}

TEST(CorrelativeMatch, FastSearchesEqualExhaustiveOnOfficeAndRoomPairs) {
  const CorrelativeConfig config = test_config(CorrelativeSearch::kExhaustive);
  for (const auto* world : {&testing::office_world(), &testing::room_world()}) {
    ScanPairOptions options;
    if (world == &testing::room_world()) options.T_world_target = SE2(-0.5, 0.4, 0.3);
    const auto pair = make_scan_pair(*world, options);
    const auto poses = expect_searches_agree(grid_for(pair.target, config), pair.source, SE2(0.1, 0.0, 0.03), config);
    EXPECT_EQ(poses[0], 21 * 21 * 37);  // +-10 steps in x and y, +-18 in theta
    EXPECT_LT(poses[1], poses[0]);
    EXPECT_LT(poses[2], poses[0] / 5);
  }
}

TEST(CorrelativeMatch, FastSearchesEqualExhaustiveOnRandomWindowsAndOffsets) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  ScanPairOptions options;
  options.beams = 120;
  const auto pair = make_scan_pair(testing::office_world(), options);
  for (int trial = 0; trial < 12; ++trial) {
    CorrelativeConfig config = test_config(CorrelativeSearch::kExhaustive);
    config.resolution = trial % 3 == 0 ? 0.03 : 0.02;
    config.levels = trial % 4 == 0 ? 3 : 0;  // a grid too shallow for the window: more, smaller top blocks
    config.linear_step = trial % 5 == 1 ? 2 * config.resolution : 0.0;
    config.window_x = 0.25 * unit(rng);
    config.window_y = 0.25 * unit(rng);
    config.window_theta = 0.1 * unit(rng);
    config.angular_step = (0.2 + 0.4 * unit(rng)) * kDeg;
    config.low_resolution_steps = 1 << (1 + trial % 4);
    const SE2 guess(0.3 * (unit(rng) - 0.5), 0.3 * (unit(rng) - 0.5), 0.1 * (unit(rng) - 0.5));
    expect_searches_agree(grid_for(pair.target, config), pair.source, guess, config);
  }
}

TEST(CorrelativeMatch, TiesGoToThePoseClosestToTheGuess) {
  // A straight wall along x, rasterised as a line and longer than the source's: every x offset
  // of the window scores the same, so every search keeps the guess's x.
  std::vector<Point2> wall;
  for (int n = 0; n <= 500; ++n) wall.emplace_back(-25.0 + 0.1 * n, 1.0);
  const PointCloud2 target = cloud_of(wall);
  std::vector<Point2> seen;
  for (int n = 0; n <= 300; ++n) seen.emplace_back(-15.0 + 0.1 * n, 0.9);  // 0.1 m nearer
  const PointCloud2 source = cloud_of(seen);
  CorrelativeConfig config = test_config(CorrelativeSearch::kExhaustive);
  config.max_segment_length = 0.2;
  config.window_theta = 0.0;
  for (auto search : {CorrelativeSearch::kExhaustive, CorrelativeSearch::kMultiResolution, CorrelativeSearch::kBranchAndBound}) {
    config.search = search;
    const MatchResult result = match_correlative(target, source, SE2(0.04, 0.0, 0.0), config);
    EXPECT_EQ(result.T_target_source.x(), 0.04);
    EXPECT_NEAR(result.T_target_source.y(), 0.1, config.resolution);
    EXPECT_EQ(result.T_target_source.theta(), 0.0);
    EXPECT_TRUE(result.degenerate);  // nothing fixes x
    EXPECT_EQ(result.covariance(2, 2), 1e6);  // theta was not searched
  }
}

// ---- Known transforms --------------------------------------------------------------------------

/// Per axis: |dx|, |dy| <= step, |dtheta| <= angular step.
::testing::AssertionResult within_one_step(const SE2& actual, const SE2& expected, const CorrelativeConfig& config) {
  const double step = config.resolution + 1e-12;
  if (std::abs(actual.x() - expected.x()) <= step && std::abs(actual.y() - expected.y()) <= step &&
      std::abs(actual.theta() - expected.theta()) <= config.angular_step + 1e-12) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << actual << " vs " << expected;
}

TEST(CorrelativeMatch, RecoversKnownTransformsWithinOneStepForwardAndInverse) {
  // The issue's sensor: 1080 beams over 270 deg, 1 cm noise; steps of 2 cm and 0.25 deg.
  const CorrelativeConfig config = test_config(CorrelativeSearch::kBranchAndBound);
  const std::vector<SE2> truths{{0.15, -0.05, 0.05}, {-0.1, 0.12, -0.04}, {0.05, 0.08, 0.0}};
  for (const auto* world : {&testing::office_world(), &testing::room_world()}) {
    for (const SE2& truth : truths) {
      ScanPairOptions options = issue_sensor();
      options.T_target_source = truth;
      if (world == &testing::room_world()) options.T_world_target = SE2(-0.5, 0.4, 0.3);
      const auto pair = make_scan_pair(*world, options);
      const MatchResult forward = match_correlative(pair.target, pair.source, SE2(), config);
      EXPECT_TRUE(forward.converged);
      EXPECT_TRUE(within_one_step(forward.T_target_source, truth, config));
      const MatchResult inverse = match_correlative(pair.source, pair.target, SE2(), config);
      EXPECT_TRUE(inverse.converged);
      EXPECT_TRUE(within_one_step(inverse.T_target_source, truth.inverse(), config));
      EXPECT_GT(forward.inliers, pair.source.size() * 9 / 10);
      EXPECT_LT(forward.residual, 0.03);
      EXPECT_FALSE(forward.degenerate);
    }
  }
}

TEST(CorrelativeMatch, RecoversFromAGuessFarFromTheTruth) {
  ScanPairOptions options;
  options.T_world_target = SE2(-0.5, 0.4, 0.3);
  options.T_target_source = SE2(0.3, -0.2, 0.25);
  const auto pair = make_scan_pair(testing::room_world(), options);
  CorrelativeConfig config;  // defaults: +-0.3 m, +-0.35 rad at 3 cm
  config.window_x = 0.5;
  config.window_y = 0.5;
  const MatchResult result = match_correlative(pair.target, pair.source, SE2(), config);
  EXPECT_TRUE(result.converged);
  EXPECT_TRUE(test::poses_near(result.T_target_source, pair.T_target_source, 0.03, 0.01)) << result.T_target_source;
}

TEST(CorrelativeMatch, PrebuiltAggregateGridMatchesAScanOfIt) {
  // The target table rasterises two scans from different poses (one frame), as a local map.
  ScanPairOptions options = issue_sensor();
  options.T_target_source = SE2(0.4, 0.1, -0.1);
  const auto first = make_scan_pair(testing::office_world(), options);
  PointCloud2 aggregate = first.target;
  for (const Point2& p : first.source.points) aggregate.points.push_back(first.T_target_source * p);
  options.T_target_source = SE2(0.2, 0.05, 0.08);
  options.seed = 3;
  const auto second = make_scan_pair(testing::office_world(), options);
  const CorrelativeConfig config = test_config(CorrelativeSearch::kBranchAndBound);
  const CorrelativeGrid grid = grid_for(aggregate, config);
  const MatchResult result = match_correlative(grid, second.source, SE2(0.1, 0.0, 0.05), config);
  EXPECT_TRUE(result.converged);
  EXPECT_TRUE(within_one_step(result.T_target_source, second.T_target_source, config));
  // The overload that builds the table gives the same match as the prebuilt one.
  const CorrelativeGrid single = grid_for(second.target, config);
  expect_same_match(match_correlative(single, second.source, SE2(), config),
                    match_correlative(second.target, second.source, SE2(), config));
}

// ---- Covariance and degeneracy -----------------------------------------------------------------

TEST(CorrelativeMatch, CovarianceGrowsAlongTheCorridorWhichIsDegenerate) {
  ScanPairOptions options;
  options.T_world_target = SE2(0.0, 0.0, 0.0);
  options.T_target_source = SE2(0.1, 0.05, 0.02);
  const auto pair = make_scan_pair(testing::corridor_world(), options);
  CorrelativeConfig config = test_config(CorrelativeSearch::kExhaustive);
  config.max_segment_length = 3.0;  // the walls as lines: sliding along them changes (almost) nothing
  const MatchResult exhaustive = match_correlative(pair.target, pair.source, SE2(), config);
  for (auto search : {CorrelativeSearch::kExhaustive, CorrelativeSearch::kBranchAndBound}) {
    config.search = search;
    const MatchResult result = match_correlative(pair.target, pair.source, SE2(), config);
    // The fast search's box grew along the corridor until it held all the response that counts.
    EXPECT_TRUE(result.covariance.isApprox(exhaustive.covariance, 1e-3)) << result.covariance;
    EXPECT_TRUE(result.degenerate);
    EXPECT_GT(std::abs(result.weak_direction.x()), 0.9) << result.weak_direction.transpose();
    EXPECT_GT(result.covariance(0, 0), 10.0 * result.covariance(1, 1)) << result.covariance;
    // Across the corridor the wall fixes y.
    EXPECT_NEAR(result.T_target_source.y(), pair.T_target_source.y(), config.resolution);
  }
}

TEST(CorrelativeMatch, RoomIsNotDegenerateAndItsCovarianceIsSmallAndValid) {
  ScanPairOptions options;
  options.T_world_target = SE2(-0.5, 0.4, 0.3);
  const auto pair = make_scan_pair(testing::room_world(), options);
  const MatchResult exhaustive = match_correlative(pair.target, pair.source, SE2(), test_config(CorrelativeSearch::kExhaustive));
  for (auto search : {CorrelativeSearch::kExhaustive, CorrelativeSearch::kBranchAndBound}) {
    const CorrelativeConfig config = test_config(search);
    const MatchResult result = match_correlative(pair.target, pair.source, SE2(), config);
    EXPECT_FALSE(result.degenerate);
    EXPECT_TRUE(result.covariance.isApprox(exhaustive.covariance, 1e-3)) << result.covariance;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(result.covariance);
    EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
    // At least the quantisation of one step, at most a few steps.
    EXPECT_GE(result.covariance(0, 0), config.resolution * config.resolution / 12.0);
    EXPECT_LT(std::sqrt(result.covariance(0, 0)), 3 * config.resolution);
    EXPECT_LT(std::sqrt(result.covariance(2, 2)), 3 * config.angular_step);
  }
}

// ---- Failures and errors -----------------------------------------------------------------------

TEST(CorrelativeMatch, EmptyOrTinyCloudsDoNotConverge) {
  const auto pair = make_scan_pair(testing::office_world());
  const SE2 guess(0.1, 0.2, 0.3);
  for (const auto& [target, source] :
       std::vector<std::pair<PointCloud2, PointCloud2>>{{PointCloud2{}, pair.source},
                                                        {pair.target, PointCloud2{}},
                                                        {pair.target, cloud_of({{1.0, 0.0}, {0.0, 1.0}})}}) {
    const MatchResult result = match_correlative(target, source, guess);
    EXPECT_FALSE(result.converged);
    EXPECT_TRUE(result.T_target_source == guess);
    EXPECT_GE(result.covariance.diagonal().minCoeff(), 1e5);
  }
  EXPECT_FALSE(match_correlative(CorrelativeGrid(), pair.source, guess).converged);
}

TEST(CorrelativeMatch, UnrelatedCloudsScoreBelowMinScore) {
  const auto pair = make_scan_pair(testing::office_world());
  std::vector<Point2> far;
  for (int n = 0; n < 50; ++n) far.emplace_back(100.0 + 0.1 * n, 100.0);
  CorrelativeConfig config = test_config(CorrelativeSearch::kBranchAndBound);
  const MatchResult result = match_correlative(pair.target, cloud_of(far), SE2(), config);
  EXPECT_FALSE(result.converged);
  EXPECT_EQ(result.inliers, 0u);
}

TEST(CorrelativeMatch, InvalidConfigurationsThrow) {
  const auto pair = make_scan_pair(testing::office_world());
  auto with = [](auto edit) {
    CorrelativeConfig config;
    edit(config);
    return config;
  };
  const std::vector<CorrelativeConfig> invalid{
      with([](auto& c) { c.resolution = 0.0; }),       with([](auto& c) { c.resolution = -0.02; }),
      with([](auto& c) { c.sigma = 0.0; }),            with([](auto& c) { c.window_x = -0.1; }),
      with([](auto& c) { c.window_y = -0.1; }),        with([](auto& c) { c.window_theta = -0.1; }),
      with([](auto& c) { c.window_theta = 4.0; }),     with([](auto& c) { c.linear_step = -0.01; }),
      with([](auto& c) { c.linear_step = 0.045; }),    with([](auto& c) { c.angular_step = -0.01; }),
      with([](auto& c) { c.min_score = 1.5; }),        with([](auto& c) { c.low_resolution_steps = 12; }),
      with([](auto& c) { c.covariance_radius = -1; }), with([](auto& c) { c.levels = 17; }),
      with([](auto& c) { c.min_eigenvalue_ratio = 0.0; }),
      with([](auto& c) { c.window_x = std::numeric_limits<double>::infinity(); }),
  };
  for (const CorrelativeConfig& config : invalid) {
    EXPECT_THROW(match_correlative(pair.target, pair.source, SE2(), config), Error);
    EXPECT_THROW(match_correlative(CorrelativeGrid(pair.target), pair.source, SE2(), config), Error);
  }
  EXPECT_THROW(match_correlative(pair.target, pair.source, SE2(std::nan(""), 0.0, 0.0)), Error);
  EXPECT_THROW(match_correlative(pair.target, cloud_of({{0.0, 0.0}, {1.0, 1.0}, {std::nan(""), 1.0}}), SE2()), Error);
  // A whole multiple of the resolution is a valid step.
  EXPECT_NO_THROW(match_correlative(pair.target, pair.source, SE2(), with([](auto& c) { c.linear_step = 0.06; })));
}

}  // namespace
}  // namespace slam2d
