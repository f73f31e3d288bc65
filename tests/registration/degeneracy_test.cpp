// SPDX-License-Identifier: BSD-3-Clause
// Degeneracy from the Fisher information: the corridor and the circular room are flagged, with
// the right weak direction; rooms with corners are not.

#include "slam2d/registration/degeneracy.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {
namespace {

using testing::make_scan_pair;
using testing::ScanPair;
using testing::ScanPairOptions;

// Nearest-point correspondences at the true pose.
std::vector<Correspondence> nearest_correspondences(const ScanPair& pair) {
  const KdTree2 tree(pair.target.points);
  std::vector<Correspondence> out;
  for (std::size_t i = 0; i < pair.source.size(); ++i) {
    const Neighbor n = tree.nearest(pair.T_target_source * pair.source.points[i]);
    if (n.squared_distance < 0.25 * 0.25) out.push_back({.source = i, .target = n.index});
  }
  return out;
}

DegeneracyAnalysis analyze(const World& world, const SE2& T_world_target) {
  ScanPairOptions options;
  options.T_world_target = T_world_target;
  options.T_target_source = SE2(0.1, 0.02, 0.02);
  const ScanPair pair = make_scan_pair(world, options);
  return analyze_degeneracy(pair.target, pair.source, pair.T_target_source, nearest_correspondences(pair));
}

TEST(Degeneracy, CorridorIsDegenerateAlongItsAxis) {
  const DegeneracyAnalysis analysis = analyze(testing::corridor_world(), SE2(0.0, 0.0, 0.0));
  EXPECT_TRUE(analysis.degenerate);
  EXPECT_GT(std::abs(analysis.weak_direction.x()), 0.99);  // along the corridor
}

TEST(Degeneracy, CircularRoomIsDegenerateInRotation) {
  const DegeneracyAnalysis analysis = analyze(testing::circular_room_world(), SE2(0.0, 0.0, 0.3));
  EXPECT_TRUE(analysis.degenerate);
  EXPECT_GT(std::abs(analysis.weak_direction.z()), 0.99);  // the heading
}

TEST(Degeneracy, RoomsWithCornersAreConstrained) {
  const DegeneracyAnalysis room = analyze(testing::room_world(), SE2(-1.0, 0.5, 0.2));
  EXPECT_FALSE(room.degenerate);
  EXPECT_GT(room.eigenvalues.x(), 0.05 * room.eigenvalues.z());
  const DegeneracyAnalysis office = analyze(testing::office_world(), SE2(7.0, 2.5, 0.3));  // room S1
  EXPECT_FALSE(office.degenerate);
}

TEST(Degeneracy, TooFewPairsIsDegenerate) {
  PointCloud2 cloud;
  cloud.points = {{1.0, 0.0}, {1.0, 1.0}};
  const DegeneracyAnalysis analysis = analyze_degeneracy(cloud, cloud, SE2(), {{.source = 0, .target = 0, .target2 = 1}});
  EXPECT_TRUE(analysis.degenerate);
}

TEST(Degeneracy, ApplyCopiesTheEigenvaluesBehindTheVerdict) {
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  information.diagonal() << 1e-3, 4e4, 9e4;  // nothing along x
  const DegeneracyAnalysis analysis = analyze_information(information, 2.0);
  MatchResult result;
  EXPECT_TRUE(result.information_eigenvalues.array().isNaN().all());  // no analysis yet
  result.covariance = Covariance3::Identity() * 1e-4;
  apply(analysis, result);
  EXPECT_TRUE(result.degenerate);
  EXPECT_EQ(result.information_eigenvalues, analysis.eigenvalues);
  EXPECT_NEAR(result.information_eigenvalues.x(), 1e-3, 1e-9);
  EXPECT_NEAR(result.information_eigenvalues.z(), 4e4, 1e-6);  // 9e4 / L^2 for rotation
}

TEST(Degeneracy, InformationDecompositionScalesRotationByLength) {
  // Information 1/m^2 in x and y and 4/rad^2 in theta, at L = 2 m: theta' = 2 theta carries 1/m^2.
  const Eigen::Matrix3d information = Eigen::Vector3d(1.0, 1.0, 4.0).asDiagonal();
  const DegeneracyAnalysis analysis = analyze_information(information, 2.0);
  EXPECT_NEAR(analysis.eigenvalues.x(), 1.0, 1e-12);
  EXPECT_NEAR(analysis.eigenvalues.z(), 1.0, 1e-12);
  EXPECT_FALSE(analysis.degenerate);
  const DegeneracyAnalysis weak = analyze_information(Eigen::Vector3d(1.0, 1e-4, 4.0).asDiagonal(), 2.0);
  EXPECT_TRUE(weak.degenerate);
  EXPECT_NEAR(std::abs(weak.weak_direction.y()), 1.0, 1e-12);
  EXPECT_THROW(analyze_information(information, 1.0, {.min_eigenvalue_ratio = 2.0}), Error);
}

}  // namespace
}  // namespace slam2d
