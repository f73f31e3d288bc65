// SPDX-License-Identifier: BSD-3-Clause
// The modular ICP pipeline (src/slam2d/registration/pipeline*.hpp): each data and outlier filter
// on hand-made clouds with hand-computed outcomes, the stages against brute force, every preset
// configs/pipeline*.yaml on simulated pairs (forward and inverse), YAML errors, code vs YAML.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/registration/pipeline.hpp"
#include "slam2d/registration/normals.hpp"
#include "slam2d/methods/pipeline_config.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using testing::make_scan_pair;
using testing::ScanPairOptions;

PointCloud2 cloud_of(const std::vector<Point2>& points) {
  PointCloud2 cloud;
  cloud.points = points;
  return cloud;
}

std::vector<PointPair> pairs_with_distances(const std::vector<double>& distances) {
  std::vector<PointPair> pairs;
  for (std::size_t i = 0; i < distances.size(); ++i) pairs.push_back({i, i, distances[i] * distances[i]});
  return pairs;
}

std::vector<std::size_t> sources_of(const std::vector<PointPair>& pairs) {
  std::vector<std::size_t> out;
  for (const PointPair& pair : pairs) out.push_back(pair.source);
  return out;
}

std::vector<PointPair> reject(const OutlierFilterConfig& filter, std::vector<PointPair> pairs,
                              const PointCloud2& target = {}, const PointCloud2& source = {},
                              const SE2& T = SE2::identity()) {
  std::vector<double> scratch;
  apply_outlier_filter(filter, {target, source, T}, pairs, scratch);
  return pairs;
}

// ---- data filters --------------------------------------------------------------------------

TEST(PipelineFilters, RangeClipKeepsTheClosedIntervalInOrderWithNormalsAndWeights) {
  PointCloud2 cloud = cloud_of({{0.05, 0.0}, {0.0, 0.1}, {0.6, 0.8}, {15.0, 20.0}, {0.0, -30.0}});
  cloud.normals = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 0}};
  cloud.weights = {1, 2, 3, 4, 5};
  apply_data_filter(cloud, RangeClipFilter{.min = 0.1, .max = 25.0});  // ranges 0.05, 0.1, 1, 25, 30
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.points[0], Point2(0.0, 0.1));
  EXPECT_EQ(cloud.points[1], Point2(0.6, 0.8));
  EXPECT_EQ(cloud.points[2], Point2(15.0, 20.0));
  EXPECT_EQ(cloud.normals, (std::vector<Point2>{{0, 1}, {-1, 0}, {0, -1}}));
  EXPECT_EQ(cloud.weights, (std::vector<double>{2, 3, 4}));
}

TEST(PipelineFilters, VoxelGridAveragesEachCellInOrderOfFirstPoint) {
  // Cells of 0.1 m: (0,0) holds points 0 and 2, (-1,0) point 1, (1,0) points 3 and 4.
  PointCloud2 cloud = cloud_of({{0.01, 0.02}, {-0.05, 0.05}, {0.03, 0.08}, {0.15, 0.01}, {0.11, 0.09}});
  cloud.normals = {{1, 0}, {0, 1}, {0, 1}, {1, 0}, {1, 0}};
  cloud.weights = {1, 2, 3, 4, 6};
  apply_data_filter(cloud, VoxelGridFilter{.size = 0.1});
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_TRUE(cloud.points[0].isApprox(Point2(0.02, 0.05)));
  EXPECT_TRUE(cloud.points[1].isApprox(Point2(-0.05, 0.05)));
  EXPECT_TRUE(cloud.points[2].isApprox(Point2(0.13, 0.05)));
  EXPECT_TRUE(cloud.normals[0].isApprox(Point2(1, 1).normalized()));
  EXPECT_TRUE(cloud.normals[1].isApprox(Point2(0, 1)));
  EXPECT_TRUE(cloud.normals[2].isApprox(Point2(1, 0)));
  EXPECT_EQ(cloud.weights, (std::vector<double>{2, 2, 5}));
}

TEST(PipelineFilters, RandomSubsampleKeepsAnExactSeededSubsetInOrder) {
  std::vector<Point2> points;
  for (int i = 0; i < 10; ++i) points.emplace_back(i, 0.0);
  PointCloud2 a = cloud_of(points);
  PointCloud2 b = cloud_of(points);
  apply_data_filter(a, RandomSubsampleFilter{.ratio = 0.3, .seed = 7});
  apply_data_filter(b, RandomSubsampleFilter{.ratio = 0.3, .seed = 7});
  ASSERT_EQ(a.size(), 3u);  // round(0.3 * 10)
  EXPECT_EQ(a.points, b.points);
  for (std::size_t k = 1; k < a.size(); ++k) EXPECT_LT(a.points[k - 1].x(), a.points[k].x());
  // Each point is kept with probability 0.3 over seeds: 2000 draws, 3 sigma ~ 0.031.
  std::vector<int> counts(10, 0);
  for (std::uint64_t seed = 0; seed < 2000; ++seed) {
    PointCloud2 c = cloud_of(points);
    apply_data_filter(c, RandomSubsampleFilter{.ratio = 0.3, .seed = seed});
    ASSERT_EQ(c.size(), 3u);
    for (const Point2& p : c.points) ++counts[static_cast<std::size_t>(p.x())];
  }
  for (int count : counts) EXPECT_NEAR(count / 2000.0, 0.3, 0.035);
  PointCloud2 one = cloud_of(points);
  apply_data_filter(one, RandomSubsampleFilter{.ratio = 0.01});
  EXPECT_EQ(one.size(), 1u);  // at least one point
}

TEST(PipelineFilters, NormalsOfAWallFaceTheSensor) {
  std::vector<Point2> wall;
  for (int i = -10; i <= 10; ++i) wall.emplace_back(0.1 * i, 2.0);
  for (const bool ordered : {false, true}) {
    PointCloud2 cloud = cloud_of(wall);
    apply_data_filter(cloud, NormalsFilter{.neighbors = 5, .ordered = ordered});
    ASSERT_EQ(cloud.normals.size(), wall.size());
    for (const Point2& normal : cloud.normals) EXPECT_TRUE(normal.isApprox(Point2(0.0, -1.0), 1e-9)) << normal;
  }
}

// ---- outlier filters -----------------------------------------------------------------------

TEST(PipelineFilters, MaxDistanceRejectsFartherPairs) {
  const auto kept = reject(MaxDistanceFilter{.distance = 0.5}, pairs_with_distances({0.1, 0.6, 0.5, 0.49, 2.0}));
  EXPECT_EQ(sources_of(kept), (std::vector<std::size_t>{0, 2, 3}));
}

TEST(PipelineFilters, TrimmedKeepsTheClosestFractionInOrder) {
  const auto pairs = pairs_with_distances({0.9, 0.1, 0.8, 0.2, 0.7, 0.3, 0.6, 0.4, 0.5, 1.0});
  EXPECT_EQ(sources_of(reject(TrimmedFilter{.ratio = 0.7}, pairs)), (std::vector<std::size_t>{1, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(reject(TrimmedFilter{.ratio = 1.0}, pairs).size(), 10u);
  EXPECT_EQ(sources_of(reject(TrimmedFilter{.ratio = 0.01}, pairs)), (std::vector<std::size_t>{1}));
  // Ties at the cut: the first ones are kept.
  const auto ties = pairs_with_distances({0.5, 0.1, 0.5, 0.5, 0.2});
  EXPECT_EQ(sources_of(reject(TrimmedFilter{.ratio = 0.8}, ties)), (std::vector<std::size_t>{0, 1, 2, 4}));
}

TEST(PipelineFilters, MedianFactorCutsAtFactorTimesTheQuantile) {
  // Median of (1, 2, 3, 4, 100) is 3: the cut at 3 x 3 = 9 drops 100.
  const auto kept = reject(MedianFactorFilter{.factor = 3.0}, pairs_with_distances({1, 100, 3, 2, 4}));
  EXPECT_EQ(sources_of(kept), (std::vector<std::size_t>{0, 2, 3, 4}));
  // Lower median of (1, 2, 3, 10) is 2: the cut at 4 drops 10.
  EXPECT_EQ(sources_of(reject(MedianFactorFilter{.factor = 2.0}, pairs_with_distances({10, 1, 3, 2}))),
            (std::vector<std::size_t>{1, 2, 3}));
  // Censi's adaptive rule on (1, 2, 3, 15, 4, ..., 10, 20): the 0.7-quantile of 12 distances is the
  // ceil(8.4) = 9th smallest, 9; the cut at 2 x 9 = 18 keeps 15 and drops 20.
  const auto adaptive = reject(MedianFactorFilter{.factor = 2.0, .quantile = 0.7},
                               pairs_with_distances({1, 2, 3, 15, 4, 5, 6, 7, 8, 9, 10, 20}));
  EXPECT_EQ(sources_of(adaptive), (std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
}

TEST(PipelineFilters, NormalAngleComparesTheRotatedSourceNormal) {
  PointCloud2 source = cloud_of({{0, 0}, {0, 0}, {0, 0}, {0, 0}});
  source.normals = {{1, 0}, {1, 0}, {0, 0}, {1, 0}};
  PointCloud2 target = cloud_of({{0, 0}, {0, 0}, {0, 0}, {0, 0}});
  const double c = std::cos(0.7);
  target.normals = {{0, 1}, {1, 0}, {0, 1}, {-std::sin(0.7), c}};  // 0, 90, -, 40 degrees from (0, 1)
  const SE2 quarter_turn(0.0, 0.0, std::numbers::pi / 2);            // source (1, 0) -> (0, 1)
  std::vector<PointPair> pairs = pairs_with_distances({0, 0, 0, 0});
  const auto kept = reject(NormalAngleFilter{.max_angle = 0.75}, pairs, target, source, quarter_turn);
  EXPECT_EQ(sources_of(kept), (std::vector<std::size_t>{0, 3}));  // 2 has no source normal
  EXPECT_EQ(sources_of(reject(NormalAngleFilter{.max_angle = 0.65}, pairs, target, source, quarter_turn)),
            (std::vector<std::size_t>{0}));
}

TEST(PipelineFilters, InvalidParametersThrow) {
  PointCloud2 cloud = cloud_of({{1, 0}});
  EXPECT_THROW(apply_data_filter(cloud, VoxelGridFilter{.size = -0.1}), Error);
  EXPECT_THROW(apply_data_filter(cloud, VoxelGridFilter{.size = 0.0}), Error);
  EXPECT_THROW(apply_data_filter(cloud, RangeClipFilter{.min = 2.0, .max = 1.0}), Error);
  EXPECT_THROW(apply_data_filter(cloud, RandomSubsampleFilter{.ratio = 1.5}), Error);
  EXPECT_THROW(apply_data_filter(cloud, NormalsFilter{.neighbors = 1}), Error);
  EXPECT_THROW(validate(OutlierFilterConfig{TrimmedFilter{.ratio = 0.0}}), Error);
  EXPECT_THROW(validate(OutlierFilterConfig{TrimmedFilter{.ratio = 1.01}}), Error);
  EXPECT_NO_THROW(validate(OutlierFilterConfig{TrimmedFilter{.ratio = 1.0}}));
  EXPECT_THROW(validate(OutlierFilterConfig{MedianFactorFilter{.factor = 0.5}}), Error);
  EXPECT_THROW(validate(OutlierFilterConfig{NormalAngleFilter{.max_angle = 4.0}}), Error);
  const PointCloud2 some = cloud_of({{1, 0}, {0, 1}, {1, 1}});
  EXPECT_THROW(match_pipeline(some, some, SE2(), {.source_filters = {VoxelGridFilter{.size = -0.1}}}), Error);
  EXPECT_THROW(match_pipeline(some, some, SE2(), {.outlier_filters = {TrimmedFilter{.ratio = 0.0}}}), Error);
  EXPECT_THROW(match_pipeline(some, some, SE2(), {.association = {.max_distance = 0.0}}), Error);
  EXPECT_THROW(match_pipeline(some, some, SE2(), {.convergence = {.max_iterations = 0}}), Error);
  EXPECT_THROW(match_pipeline(some, some, SE2(), {.min_inliers = 2}), Error);
}

// ---- stages --------------------------------------------------------------------------------

// The closest target point within max_distance of each moved source point, by brute force.
std::vector<PointPair> brute_force_pairs(const PointCloud2& target, const PointCloud2& source, const SE2& T,
                                         double max_distance) {
  std::vector<PointPair> expected;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const Point2 moved = T * source.points[i];
    std::size_t best = 0;
    for (std::size_t j = 1; j < target.size(); ++j) {
      if ((target.points[j] - moved).squaredNorm() < (target.points[best] - moved).squaredNorm()) best = j;
    }
    const double d2 = (target.points[best] - moved).squaredNorm();
    if (d2 <= max_distance * max_distance) expected.push_back({i, best, d2});
  }
  return expected;
}

void expect_same_pairs(const std::vector<PointPair>& pairs, const std::vector<PointPair>& expected) {
  ASSERT_EQ(pairs.size(), expected.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_EQ(pairs[k].source, expected[k].source);
    EXPECT_EQ(pairs[k].target, expected[k].target);
    EXPECT_DOUBLE_EQ(pairs[k].squared_distance, expected[k].squared_distance);
  }
}

TEST(PipelineStages, AssociationAgreesWithBruteForce) {
  // Both searches are exact: the kd-tree and PL-ICP's projective search, also when the index is
  // reused at other estimates (the projective search's certificates carry over) and on a target
  // that is not in beam order (the projective search falls back to a kd-tree).
  const auto pair = make_scan_pair(testing::room_world(), {.T_world_target = SE2(0.5, -0.3, 0.4), .beams = 360,
                                                            .field_of_view = 2 * std::numbers::pi});
  PointCloud2 shuffled = pair.target;
  Rng rng(5);
  for (std::size_t k = shuffled.size() - 1; k > 0; --k) {
    std::swap(shuffled.points[k], shuffled.points[static_cast<std::size_t>(rng.uniform(0.0, 1.0) * static_cast<double>(k + 1)) % (k + 1)]);
  }
  const double max_distance = 0.3;
  for (const PointCloud2* target : {&pair.target, static_cast<const PointCloud2*>(&shuffled)}) {
    for (const AssociationKind kind : {AssociationKind::kKdTree, AssociationKind::kProjective}) {
      const TargetIndex index(*target, {.kind = kind, .max_distance = max_distance});
      for (const SE2& offset : {SE2(), SE2(0.05, -0.02, 0.01), SE2(-0.2, 0.1, -0.08), SE2()}) {
        SCOPED_TRACE(::testing::Message() << "kind " << static_cast<int>(kind) << " offset " << offset);
        const SE2 T = offset * pair.T_target_source;
        std::vector<PointPair> pairs;
        index.associate(pair.source.points, T, pairs);
        EXPECT_GT(pairs.size(), pair.source.size() / 2);
        expect_same_pairs(pairs, brute_force_pairs(*target, pair.source, T, max_distance));
      }
    }
  }
}

TEST(PipelineStages, MinimizersRecoverAnExactMotion) {
  // Target: the outline of an L-shaped room; source: the same points moved by the inverse motion.
  PointCloud2 target;
  for (int i = 0; i <= 40; ++i) target.points.emplace_back(-2.0 + 0.1 * i, 3.0);
  for (int i = 0; i <= 30; ++i) target.points.emplace_back(2.0, 3.0 - 0.1 * i);
  for (int i = 0; i <= 20; ++i) target.points.emplace_back(-2.0, 1.0 + 0.1 * i);
  estimate_normals(target);
  const SE2 motion(0.05, -0.03, 0.02);
  PointCloud2 source;
  std::vector<PointPair> pairs;
  for (std::size_t j = 0; j < target.size(); ++j) {
    source.points.push_back(motion.inverse() * target.points[j]);
    pairs.push_back({j, j, (source.points.back() - target.points[j]).squaredNorm()});
  }
  keep_pairs_with_normals(target, pairs);
  PairedPoints paired;
  const auto p2p = minimize_step(Minimizer::kPointToPoint, target, source, SE2(), pairs, paired);
  ASSERT_TRUE(p2p);
  EXPECT_TRUE(p2p->step.is_approx(motion, 1e-12)) << p2p->step;
  // Point-to-line: the small-angle step lands within O(theta^2) and converges on iteration.
  SE2 T;
  for (int k = 0; k < 5; ++k) {
    const auto step = minimize_step(Minimizer::kPointToLine, target, source, T, pairs, paired);
    ASSERT_TRUE(step);
    T = step->step * T;
  }
  EXPECT_TRUE(T.is_approx(motion, 1e-9)) << T;
}

// ---- the whole pipeline --------------------------------------------------------------------

std::vector<std::string> preset_paths() {
  std::vector<std::string> paths;
  for (const auto& entry : std::filesystem::directory_iterator("configs")) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("pipeline", 0) == 0 && entry.path().extension() == ".yaml") paths.push_back(entry.path().string());
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

TEST(PipelineMatch, EveryPresetRecoversKnownTransformsForwardAndInverse) {
  const auto paths = preset_paths();
  ASSERT_GE(paths.size(), 4u) << "configs/pipeline*.yaml not found (run from the repository root)";
  struct Case {
    const World* world;
    SE2 T_world_target;
    SE2 T_target_source;
  };
  const std::vector<Case> cases = {
      {&testing::office_world(), SE2(6.5, 2.0, 0.3), SE2(0.15, -0.05, 0.05)},
      {&testing::office_world(), SE2(7.0, 2.5, -0.4), SE2(-0.1, 0.1, -0.08)},
      {&testing::room_world(), SE2(0.5, -0.5, 0.3), SE2(0.2, 0.1, 0.1)},
      {&testing::room_world(), SE2(-1.0, 0.5, -2.0), SE2(-0.15, 0.2, -0.12)},
  };
  for (const std::string& path : paths) {
    const PipelineConfig config = load_pipeline_config(path);
    // Point-to-point presets carry that metric's bias on partly overlapping scans (icp_test.cpp).
    const bool point_to_point = config.minimizer == Minimizer::kPointToPoint;
    const double translation_bound = point_to_point ? 0.05 : 0.02;  // m
    const double rotation_bound = point_to_point ? 0.025 : 0.005;   // rad
    for (std::size_t c = 0; c < cases.size(); ++c) {
      const auto pair = make_scan_pair(*cases[c].world, {.T_world_target = cases[c].T_world_target,
                                                         .T_target_source = cases[c].T_target_source,
                                                         .beams = 720,  // point-to-point's sampling bias is 0.01 rad at 180
                                                         .seed = 10 + c});
      const MatchResult forward = match_pipeline(pair.target, pair.source, SE2(), config);
      EXPECT_TRUE(forward.converged) << path << " case " << c;
      EXPECT_TRUE(test::poses_near(forward.T_target_source, pair.T_target_source, translation_bound, rotation_bound))
          << path << " case " << c << ": " << forward.T_target_source;
      EXPECT_GT(forward.inliers, 60u);
      EXPECT_LT(forward.residual, point_to_point ? 0.1 : 0.05);
      EXPECT_FALSE(forward.degenerate) << path << " case " << c;
      EXPECT_LT(forward.covariance(0, 0), 1e-3);
      const MatchResult inverse = match_pipeline(pair.source, pair.target, SE2(), config);
      EXPECT_TRUE(inverse.converged) << path << " case " << c;
      EXPECT_TRUE(
          test::poses_near(inverse.T_target_source, pair.T_target_source.inverse(), translation_bound, rotation_bound))
          << path << " inverse case " << c << ": " << inverse.T_target_source;
    }
  }
}

TEST(PipelineMatch, EmptyAndTinyCloudsFailWithAHugeCovariance) {
  const auto pair = make_scan_pair(testing::office_world());
  const SE2 guess(0.1, 0.2, 0.3);
  const PointCloud2 empty;
  const PointCloud2 two = cloud_of({{1, 0}, {0, 1}});
  for (const MatchResult& r : {match_pipeline(pair.target, empty, guess), match_pipeline(empty, pair.source, guess),
                               match_pipeline(empty, empty, guess), match_pipeline(two, two, guess)}) {
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.T_target_source, guess);
    EXPECT_GE(r.covariance.diagonal().minCoeff(), 1e5);
    EXPECT_TRUE(r.degenerate);
  }
  // Non-overlapping clouds: no pair within reach.
  PointCloud2 far = pair.source;
  for (Point2& p : far.points) p += Point2(500.0, 0.0);
  EXPECT_FALSE(match_pipeline(pair.target, far, SE2()).converged);
  // Non-finite points are dropped, not propagated.
  PointCloud2 with_nan = pair.source;
  with_nan.points[3] = Point2(std::numeric_limits<double>::quiet_NaN(), 1.0);
  const MatchResult r = match_pipeline(pair.target, with_nan, SE2());
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(r.T_target_source.vector().allFinite());
}

TEST(PipelineMatch, ConvergenceChecks) {
  const auto pair = make_scan_pair(testing::office_world());
  PipelineConfig one_step;
  one_step.convergence.max_iterations = 1;
  const MatchResult r1 = match_pipeline(pair.target, pair.source, SE2(), one_step);
  EXPECT_EQ(r1.iterations, 1);
  EXPECT_FALSE(r1.converged);  // the iteration limit is not convergence
  PipelineConfig by_error{.convergence = {.max_iterations = 100, .translation = 0.0, .rotation = 0.0,
                                          .error_change = 1e-3}};
  const MatchResult r2 = match_pipeline(pair.target, pair.source, SE2(), by_error);
  EXPECT_TRUE(r2.converged);
  EXPECT_LT(r2.iterations, 100);
  PipelineConfig never{.convergence = {.max_iterations = 15, .translation = 0.0, .rotation = 0.0}};
  const MatchResult r3 = match_pipeline(pair.target, pair.source, SE2(), never);
  EXPECT_EQ(r3.iterations, 15);
  EXPECT_FALSE(r3.converged);
}

TEST(PipelineMatch, CorridorIsFlaggedDegenerate) {
  const auto corridor = make_scan_pair(testing::corridor_world(), {.T_world_target = SE2(0.0, 0.0, 0.0),
                                                                   .T_target_source = SE2(0.1, 0.02, 0.01)});
  const MatchResult r = match_pipeline(corridor.target, corridor.source, SE2());
  EXPECT_TRUE(r.degenerate);
  EXPECT_GT(std::abs(r.weak_direction.x()), 0.9) << r.weak_direction.transpose();
}

// ---- YAML ----------------------------------------------------------------------------------

std::string write_file(const test::TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::ofstream(path) << text;
  return path;
}

TEST(PipelineYaml, YamlErrorsNameFileAndLine) {
  const test::TempDir dir;
  const auto load = [](const std::string& path) { load_pipeline_config(path); };
  test::expect_parse_error(load, write_file(dir, "a.yaml", "matcher: pipeline\nminimiser: point_to_line\n"), 2,
                           "unknown key 'minimiser'");
  test::expect_parse_error(load,
                           write_file(dir, "b.yaml", "source_filters:\n  - kind: voxel\n    sise: 0.05\n"), 3,
                           "unknown key 'sise'");
  test::expect_parse_error(load, write_file(dir, "c.yaml", "association:\n  kind: kdtree\n  max_distance: far\n"), 3,
                           "finite number");
  test::expect_parse_error(load, write_file(dir, "d.yaml", "outlier_filters: [{kind: trimmed, factor: 2.0}]\n"), 1,
                           "unknown key 'factor'");  // a key of another kind
  test::expect_parse_error(load, write_file(dir, "e.yaml", "\nconvergence: {max_iterations: 2.5}\n"), 2,
                           "integer");
  test::expect_parse_error(load, write_file(dir, "f.yaml", "target_filters:\n  - kind: smooth\n"), 2, "smooth");
  test::expect_parse_error(load, write_file(dir, "g.yaml", "matcher: icp\n"), 1, "pipeline");
  test::expect_parse_error(load, write_file(dir, "h.yaml", "minimizer: point_to_curve\n"), 1, "point_to_curve");
  // Out-of-range values are ParseErrors at their line.
  test::expect_parse_error(load, write_file(dir, "i.yaml", "source_filters:\n\n  - {kind: voxel, size: -0.1}\n"), 3,
                           "'size' = -0.1 is out of range (must be > 0)");
  test::expect_parse_error(load, write_file(dir, "j.yaml", "outlier_filters:\n  - kind: trimmed\n    ratio: 1.5\n"),
                           3, "'ratio' = 1.5 is out of range (must be in (0, 1])");
  // What involves two fields: the file's root.
  test::expect_parse_error(load, write_file(dir, "l.yaml", "source_filters: [{kind: range_clip, min: 5, max: 2}]\n"), 1,
                           "max must be > min");
  test::expect_parse_error(load, write_file(dir, "k.yaml", "source_filters: 3\n"), 1, "list");
}

TEST(PipelineYaml, DefaultPresetIsTheLibraryDefault) {
  EXPECT_TRUE(load_pipeline_config("configs/pipeline.yaml") == PipelineConfig{});
  EXPECT_TRUE(pipeline_config_from(ConfigNode::parse("")) == PipelineConfig{});
  const PipelineConfig none = pipeline_config_from(ConfigNode::parse("target_filters: []\noutlier_filters: []\n"));
  EXPECT_TRUE(none.target_filters.empty());
  EXPECT_TRUE(none.outlier_filters.empty());
}

TEST(PipelineYaml, CodeAndYamlGiveTheIdenticalResult) {
  const PipelineConfig from_code{
      .source_filters = {RangeClipFilter{.min = 0.1, .max = 25.0}, VoxelGridFilter{.size = 0.05},
                         RandomSubsampleFilter{.ratio = 0.8, .seed = 5}, NormalsFilter{.neighbors = 7}},
      .target_filters = {NormalsFilter{.neighbors = 3, .min_neighbors = 2, .ordered = true}},
      .association = {.kind = AssociationKind::kProjective, .max_distance = 0.5},
      .outlier_filters = {TrimmedFilter{.ratio = 0.95}, MedianFactorFilter{.factor = 2.0, .quantile = 0.7},
                          NormalAngleFilter{.max_angle = 0.5}, MaxDistanceFilter{.distance = 0.4}},
      .minimizer = Minimizer::kPointToLine,
      .convergence = {.max_iterations = 30, .translation = 1e-5, .rotation = 2e-5, .error_change = 1e-7},
      .min_inliers = 20,
      .range_sigma = 0.02};
  const PipelineConfig from_yaml = pipeline_config_from(ConfigNode::parse(R"(
matcher: pipeline
source_filters:
  - {kind: range_clip, min: 0.1, max: 25.0}
  - {kind: voxel, size: 0.05}
  - {kind: random, ratio: 0.8, seed: 5}
  - {kind: normals, neighbors: 7}
target_filters: [{kind: normals, neighbors: 3, min_neighbors: 2, ordered: true}]
association: {kind: projective, max_distance: 0.5}
outlier_filters:
  - {kind: trimmed, ratio: 0.95}
  - {kind: median_factor, factor: 2.0, quantile: 0.7}
  - {kind: normal_angle, max_angle: 0.5}
  - {kind: max_distance, distance: 0.4}
minimizer: point_to_plane
convergence: {max_iterations: 30, translation: 1.0e-5, rotation: 2.0e-5, error_change: 1.0e-7}
min_inliers: 20
range_sigma: 0.02
)"));
  EXPECT_TRUE(from_code == from_yaml);
  const auto pair = make_scan_pair(testing::office_world());
  const MatchResult a = match_pipeline(pair.target, pair.source, SE2(), from_code);
  const MatchResult b = match_pipeline(pair.target, pair.source, SE2(), from_yaml);
  EXPECT_TRUE(a.converged);
  EXPECT_EQ(a.T_target_source, b.T_target_source);
  EXPECT_EQ(a.covariance, b.covariance);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_TRUE(test::poses_near(a.T_target_source, pair.T_target_source, 0.02, 0.005)) << a.T_target_source;
}

}  // namespace
}  // namespace slam2d
