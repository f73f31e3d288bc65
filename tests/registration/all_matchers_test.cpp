// SPDX-License-Identifier: BSD-3-Clause
// One battery for every matcher of the registry (STYLE.md: a new variant gets the whole suite):
// known transforms recovered from simulated scan pairs under noise, forward and inverse; an
// honest covariance; the corridor flagged degenerate and the room not; empty input refused;
// every preset in configs/ loads and works.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <ostream>
#include <string>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/methods/matcher_registry.hpp"

namespace slam2d {
namespace {

struct Scene {
  const char* name;
  const World& (*world)();
  SE2 T_world_target;
};

const Scene kScenes[] = {
    {"office_s1_door", testing::office_world, SE2(6.5, 2.0, 0.3)},
    {"office_s1_desk", testing::office_world, SE2(7.0, 2.5, -0.4)},
    {"room", testing::room_world, SE2(-1.0, 0.5, 0.2)},
};

struct Tolerance {
  double translation = 0.04;  // m
  double rotation = 0.015;    // rad
};

// Point-to-point matchers on 1 deg scans converge ~0.01 rad off the truth, and plain ICP has no
// rejection for what only one scan sees (icp_test.cpp): their bounds are wider.
Tolerance tolerance_for(const std::string& matcher) {
  for (const char* point_to_point : {"icp", "icp-accelerated", "boolean-icp", "ga-icp"}) {
    if (matcher == point_to_point) return {0.05, 0.025};
  }
  return {};
}

::testing::AssertionResult near_pose(const SE2& estimate, const SE2& truth, const Tolerance& tolerance) {
  const SE2 error = truth.inverse() * estimate;
  if (error.translation().norm() <= tolerance.translation && std::abs(normalize_angle(error.theta())) <= tolerance.rotation) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "error " << error.translation().norm() << " m, " << error.theta()
                                       << " rad (estimate " << estimate.x() << ", " << estimate.y() << ", "
                                       << estimate.theta() << "; truth " << truth.x() << ", " << truth.y() << ", "
                                       << truth.theta() << ")";
}

class AllMatchers : public ::testing::TestWithParam<std::string> {};

TEST_P(AllMatchers, RecoversKnownTransformsForwardAndInverse) {
  const Matcher matcher = make_matcher(GetParam());
  const Tolerance tolerance = tolerance_for(GetParam());
  const SE2 guess_error(0.06, -0.04, 0.03);
  for (const Scene& scene : kScenes) {
    for (const double sigma : {0.0, 0.01, 0.03}) {
      testing::ScanPairOptions options;
      options.T_world_target = scene.T_world_target;
      options.T_target_source = SE2(0.2, -0.08, 0.06);
      options.range_sigma = sigma;
      options.dropout_probability = 0.01;
      const testing::ScanPair pair = testing::make_scan_pair(scene.world(), options);
      SCOPED_TRACE(std::string(scene.name) + ", sigma " + std::to_string(sigma));
      const MatchResult forward = matcher(pair.target, pair.source, pair.T_target_source * guess_error);
      EXPECT_TRUE(near_pose(forward.T_target_source, pair.T_target_source, tolerance));
      EXPECT_TRUE(forward.converged);
      EXPECT_GT(forward.inliers, pair.source.size() / 2);
      const SE2 inverse_truth = pair.T_target_source.inverse();
      const MatchResult inverse = matcher(pair.source, pair.target, inverse_truth * guess_error);
      EXPECT_TRUE(near_pose(inverse.T_target_source, inverse_truth, tolerance));
    }
  }
}

TEST_P(AllMatchers, ReportsAConstrainedMatchInARoomWithAnHonestCovariance) {
  const Matcher matcher = make_matcher(GetParam());
  testing::ScanPairOptions options;
  options.T_world_target = SE2(-1.0, 0.5, 0.2);
  const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), options);
  const MatchResult result = matcher(pair.target, pair.source, pair.T_target_source * SE2(0.05, 0.05, 0.02));
  EXPECT_FALSE(result.degenerate);
  EXPECT_TRUE(is_valid_covariance(result.covariance));
  // A few centimetres and a degree or so at most for 180 beams with 1 cm noise, not the "unknown" 1e6.
  EXPECT_LT(std::sqrt(result.covariance(0, 0)), 0.05);
  EXPECT_LT(std::sqrt(result.covariance(2, 2)), 0.03);
  EXPECT_GT(result.covariance.diagonal().minCoeff(), 0.0);
  EXPECT_GE(result.residual, 0.0);
  EXPECT_LT(result.residual, 0.2);
}

TEST_P(AllMatchers, FlagsTheCorridorAsDegenerateAlongItsAxis) {
  const Matcher matcher = make_matcher(GetParam());
  testing::ScanPairOptions options;
  options.T_world_target = SE2(0.0, 0.0, 0.0);
  options.T_target_source = SE2(0.3, 0.05, 0.02);
  const testing::ScanPair pair = testing::make_scan_pair(testing::corridor_world(), options);
  const MatchResult result = matcher(pair.target, pair.source, pair.T_target_source * SE2(0.05, 0.02, 0.01));
  EXPECT_TRUE(result.degenerate);
  EXPECT_GT(std::abs(result.weak_direction.x()), 0.9) << result.weak_direction.transpose();
  // Across the corridor and in heading the match still holds.
  const SE2 error = pair.T_target_source.inverse() * result.T_target_source;
  EXPECT_LT(std::abs(error.y()), 0.04);
  EXPECT_LT(std::abs(normalize_angle(error.theta())), 0.02);
}

TEST_P(AllMatchers, RefusesEmptyAndTinyClouds) {
  const Matcher matcher = make_matcher(GetParam());
  const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), {.T_world_target = SE2(-1.0, 0.5, 0.2)});
  const PointCloud2 empty;
  const PointCloud2 two{.points = {{1.0, 0.0}, {0.0, 1.0}}, .normals = {}, .weights = {}};
  for (const auto& [target, source] : {std::pair{&pair.target, &empty}, std::pair{&empty, &pair.source},
                                       std::pair{&two, &two}}) {
    const MatchResult result = matcher(*target, *source, SE2(0.1, 0.0, 0.0));
    EXPECT_FALSE(result.converged);
    EXPECT_GE(result.covariance.diagonal().minCoeff(), 1.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, AllMatchers, ::testing::ValuesIn(matcher_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& c : name) c = c == '-' ? '_' : c;
                           return name;
                         });

// Every preset in configs/ that names a matcher loads, and the matcher it makes recovers a pose.
TEST(MatcherPresets, EveryPresetLoadsAndMatches) {
  int presets = 0;
  for (const auto& entry : std::filesystem::directory_iterator("configs")) {
    if (entry.path().extension() != ".yaml") continue;
    const ConfigNode node = ConfigNode::load(entry.path().string());
    if (!node.has("matcher") || !node.at("matcher").is_scalar()) continue;  // another stage's (hector.yaml)
    SCOPED_TRACE(entry.path().string());
    const Matcher matcher = load_matcher(entry.path().string());
    const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), {.T_world_target = SE2(-1.0, 0.5, 0.2)});
    const MatchResult result = matcher(pair.target, pair.source, pair.T_target_source * SE2(0.05, 0.0, 0.02));
    EXPECT_TRUE(near_pose(result.T_target_source, pair.T_target_source, tolerance_for(node.at("matcher").as_string())));
    ++presets;
  }
  EXPECT_GE(presets, static_cast<int>(matcher_names().size()));
}

TEST(MatcherRegistry, UnknownNamesAndMismatchedPresetsAreErrors) {
  EXPECT_THROW(make_matcher("no-such-matcher"), Error);
  EXPECT_THROW(make_matcher("icp", ConfigNode::parse("matcher: pl-icp\n", "p.yaml")), ParseError);
  EXPECT_THROW(make_matcher("icp", ConfigNode::parse("max_itrations: 3\n", "typo.yaml")), ParseError);
  EXPECT_THROW(make_matcher("icp", ConfigNode::parse("max_iterations: -3\n", "bad.yaml")), Error);
  EXPECT_THROW(matcher_from_argument("configs/no-such-preset.yaml"), Error);
}

}  // namespace
}  // namespace slam2d
