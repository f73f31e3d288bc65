// SPDX-License-Identifier: BSD-3-Clause
// The tangent-based rotation search (Lu & Milios 1997 Sec. 3, registration/tangent_search.*):
// known transforms forward and inverse, a 0.5 rad turn from the identity guess, the histogram
// search alone on a hand-made turned copy, the corridor flagged, refusals, the preset reader.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/registration/normals.hpp"
#include "slam2d/registration/tangent_search.hpp"

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

// Point-to-line least squares on 7-point tangent fits: within about 1 cm and 3 mrad on these
// 1 cm-noise scans; the bounds leave a margin.
constexpr double kTranslationTolerance = 0.02;  // m
constexpr double kRotationTolerance = 0.008;    // rad

TEST(TangentSearch, RecoversKnownTransformsForwardAndInverse) {
  const std::vector<std::pair<std::string, testing::ScanPair>> cases{
      {"office", testing::make_scan_pair(testing::office_world(), {})},
      {"room", testing::make_scan_pair(testing::room_world(), {.T_world_target = SE2(0.5, -0.3, 0.2)})}};
  for (const auto& [name, pair] : cases) {
    SCOPED_TRACE(name);
    const MatchResult forward = match_tangent_search(pair.target, pair.source, SE2());
    const PoseError f = pose_error(forward.T_target_source, pair.T_target_source);
    EXPECT_LT(f.translation, kTranslationTolerance);
    EXPECT_LT(f.rotation, kRotationTolerance);
    EXPECT_TRUE(forward.converged);
    EXPECT_FALSE(forward.degenerate);
    EXPECT_GT(forward.inliers, pair.source.size() / 2);
    EXPECT_GT(forward.residual, 0.0);
    EXPECT_LT(forward.residual, 0.03);
    EXPECT_LT(std::sqrt(forward.covariance(0, 0)), 0.05);
    const MatchResult inverse = match_tangent_search(pair.source, pair.target, SE2());
    const PoseError i = pose_error(inverse.T_target_source, pair.T_target_source.inverse());
    EXPECT_LT(i.translation, kTranslationTolerance);
    EXPECT_LT(i.rotation, kRotationTolerance);
    EXPECT_TRUE(inverse.converged);
  }
}

TEST(TangentSearch, RecoversAHalfRadianTurnFromTheIdentityGuess) {
  for (const double turn : {0.5, -0.5}) {
    const testing::ScanPair pair = testing::make_scan_pair(
        testing::room_world(), {.T_world_target = SE2(0.5, -0.3, 0.2), .T_target_source = SE2(0.1, -0.05, turn)});
    const MatchResult result = match_tangent_search(pair.target, pair.source, SE2());
    const PoseError error = pose_error(result.T_target_source, pair.T_target_source);
    EXPECT_LT(error.translation, kTranslationTolerance) << turn;
    EXPECT_LT(error.rotation, kRotationTolerance) << turn;
    EXPECT_TRUE(result.converged);
  }
}

// The histogram search alone: a copy of a scan turned by 0.4 rad about its origin has the same
// tangents turned by 0.4 rad, so Eq. (1) finds 0.4 within a fraction of a 1 deg bin.
TEST(TangentSearch, HistogramSearchFindsTheTurnOfATurnedCopy) {
  const testing::ScanPair pair = testing::make_scan_pair(testing::office_world(), {.range_sigma = 0.0});
  PointCloud2 target{.points = pair.target.points, .normals = {}, .weights = {}};
  PointCloud2 turned;
  const SE2 turn(0.0, 0.0, 0.4);
  for (const Point2& p : target.points) turned.points.push_back(turn.inverse() * p);  // T_target_source = turn
  estimate_normals_ordered(target, {.neighbors = 7});
  estimate_normals_ordered(turned, {.neighbors = 7});
  EXPECT_NEAR(tangent_histogram_rotation(target, turned, 0.0), 0.4, 0.005);
  EXPECT_NEAR(tangent_histogram_rotation(target, turned, 0.3), 0.4, 0.005);
  // Outside the window the search cannot reach it.
  EXPECT_LT(tangent_histogram_rotation(target, turned, 0.0, {.max_rotation = 0.2}), 0.21);
}

TEST(TangentSearch, FlagsTheCorridorAsDegenerateAlongItsAxis) {
  const testing::ScanPair pair = testing::make_scan_pair(
      testing::corridor_world(), {.T_world_target = SE2(), .T_target_source = SE2(0.3, 0.05, 0.02)});
  const MatchResult result = match_tangent_search(pair.target, pair.source, pair.T_target_source * SE2(0.05, 0.02, 0.01));
  EXPECT_TRUE(result.degenerate);
  EXPECT_GT(std::abs(result.weak_direction.x()), 0.9);
  const SE2 error = pair.T_target_source.inverse() * result.T_target_source;
  EXPECT_LT(std::abs(error.y()), 0.02);
  EXPECT_LT(std::abs(normalize_angle(error.theta())), 0.01);
  EXPECT_GT(result.covariance(0, 0), 10.0 * result.covariance(1, 1));  // nothing fixes x: the variance says so
}

TEST(TangentSearch, EmptyAndTinyCloudsAreNotConverged) {
  const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), {.T_world_target = SE2(0.5, -0.3, 0.2)});
  const PointCloud2 empty;
  const PointCloud2 two{.points = {{1.0, 0.0}, {0.0, 1.0}}, .normals = {}, .weights = {}};
  for (const auto& [target, source] :
       {std::pair{&pair.target, &empty}, std::pair{&empty, &pair.source}, std::pair{&two, &two}}) {
    const MatchResult result = match_tangent_search(*target, *source, SE2(0.1, 0.0, 0.0));
    EXPECT_FALSE(result.converged);
    EXPECT_GE(result.covariance.diagonal().minCoeff(), 1.0);
  }
}

TEST(TangentSearch, InvalidConfigsThrow) {
  EXPECT_THROW(validate(TangentSearchConfig{.tangent_neighbors = 2}), Error);
  EXPECT_THROW(validate(TangentSearchConfig{.histogram_bins = 4}), Error);
  EXPECT_THROW(validate(TangentSearchConfig{.max_rotation = 2.0}), Error);
  EXPECT_THROW(validate(TangentSearchConfig{.max_distance_final = 5.0}), Error);
  EXPECT_THROW(validate(TangentSearchConfig{.max_tangent_difference = 0.0}), Error);
  EXPECT_THROW(validate(TangentSearchConfig{.rotation_search_width = -0.1}), Error);
  EXPECT_THROW(validate(TangentSearchConfig{.min_correspondences = 1}), Error);
  EXPECT_NO_THROW(validate(TangentSearchConfig{}));
  const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), {});
  EXPECT_THROW(match_tangent_search(pair.target, pair.source, SE2(), {.histogram_sigma = 0.0}), Error);
}

TEST(TangentSearch, ReadsEveryFieldOfAPreset) {
  const ConfigNode node = ConfigNode::parse(
      "tangent_neighbors: 9\ntangent_max_distance: 0.4\nhistogram_bins: 90\nhistogram_sigma: 0.03\n"
      "max_rotation: 0.5\nmax_iterations: 12\nmax_distance_initial: 0.8\nmax_distance_final: 0.1\n"
      "max_distance_decay: 0.2\nmax_tangent_difference: 0.25\nrotation_search_width: 0.04\n"
      "translation_tolerance: 0.001\nrotation_tolerance: 0.0001\nmin_correspondences: 8\nrange_sigma: 0.02\n",
      "tangent.yaml");
  TangentSearchConfig config;
  read_config(node, config);  // its field table; every key known
  EXPECT_EQ(config.tangent_neighbors, 9);
  EXPECT_EQ(config.tangent_max_distance, 0.4);
  EXPECT_EQ(config.histogram_bins, 90);
  EXPECT_EQ(config.histogram_sigma, 0.03);
  EXPECT_EQ(config.max_rotation, 0.5);
  EXPECT_EQ(config.max_iterations, 12);
  EXPECT_EQ(config.max_distance_initial, 0.8);
  EXPECT_EQ(config.max_distance_final, 0.1);
  EXPECT_EQ(config.max_distance_decay, 0.2);
  EXPECT_EQ(config.max_tangent_difference, 0.25);
  EXPECT_EQ(config.rotation_search_width, 0.04);
  EXPECT_EQ(config.translation_tolerance, 0.001);
  EXPECT_EQ(config.rotation_tolerance, 0.0001);
  EXPECT_EQ(config.min_correspondences, 8);
  EXPECT_EQ(config.range_sigma, 0.02);
  EXPECT_THROW(read_config(ConfigNode::parse("histogram_bins: many\n", "bad.yaml"), config), ParseError);
  EXPECT_THROW(read_config(ConfigNode::parse("histogram_bins: 4\n", "range.yaml"), config), ParseError);  // >= 8
}

}  // namespace
}  // namespace slam2d
