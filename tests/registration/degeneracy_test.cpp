// SPDX-License-Identifier: BSD-3-Clause
// Degeneracy from the Fisher information: the corridor and the circular room are flagged, with
// the right weak direction; rooms with corners are not.

#include "slam2d/registration/degeneracy.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>

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

// End points in beam order, one a degree over the front half, of walls at y = +-1.2 m (a corridor
// along x), out to 25 m.
std::vector<Eigen::Vector2d> corridor_points() {
  std::vector<Eigen::Vector2d> points;
  for (int k = -89; k <= 89; ++k) {
    const double angle = k * std::numbers::pi / 180.0;
    if (k == 0) continue;
    const double range = 1.2 / std::abs(std::sin(angle));
    if (range < 25.0) points.emplace_back(range * std::cos(angle), range * std::sin(angle));
  }
  return points;
}

// The weak over strong eigenvalue of the translational information (the rotation marginalised).
double translation_ratio(const Eigen::Matrix3d& information) {
  const Eigen::Matrix2d t = information.topLeftCorner<2, 2>() -
                            information.block<2, 1>(0, 2) * information.block<1, 2>(2, 0) / information(2, 2);
  const Eigen::Vector2d eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(t).eigenvalues();
  return eigenvalues(0) / eigenvalues(1);
}

TEST(ScanGeometry, ACorridorScanCarriesNothingAlongItsAxisAndARoomScanCarriesEverything) {
  const Eigen::Matrix3d corridor = scan_geometry(corridor_points()).information;
  EXPECT_LT(corridor(0, 0), 1e-6 * corridor(1, 1));  // the walls' normals are all along y
  EXPECT_LT(translation_ratio(corridor), 1e-6);
  // A square room 4 m across, seen from off its centre: walls in both directions.
  std::vector<Eigen::Vector2d> room;
  for (int k = 0; k < 360; ++k) {
    const Eigen::Vector2d d(std::cos(k * std::numbers::pi / 180.0), std::sin(k * std::numbers::pi / 180.0));
    const double to_x = d.x() > 0.0 ? 1.5 / d.x() : 2.5 / -d.x();
    const double to_y = d.y() > 0.0 ? 2.2 / d.y() : 1.8 / -d.y();
    room.push_back(std::min(to_x, to_y) * d);
  }
  EXPECT_GT(translation_ratio(scan_geometry(room).information), 0.5);
}

TEST(ScanGeometry, LoneReturnsBetweenTwoSurfacesAddNothing) {
  // Mixed pixels: every other beam of a stretch lands half way to a wall 10 m behind the near one.
  const std::vector<Eigen::Vector2d> clean = corridor_points();
  std::vector<Eigen::Vector2d> mixed;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    mixed.push_back(clean[i]);
    if (i % 2 == 0 && i > 40 && i < 80) mixed.push_back(clean[i] * 4.0);  // 3-40 m out, metres apart
  }
  const Eigen::Matrix3d a = scan_geometry(clean).information;
  const Eigen::Matrix3d b = scan_geometry(mixed).information;
  EXPECT_LT(translation_ratio(b), 1e-6);  // still nothing along the corridor
  EXPECT_LE(b(1, 1), a(1, 1));            // the interleaved stretch loses its chords and adds nothing
  EXPECT_GT(b(1, 1), 0.3 * a(1, 1));
  EXPECT_TRUE(scan_geometry({{1.0, 0.0}, {5.0, 3.0}, {-2.0, 7.0}}).information.isZero());  // no surface
}

TEST(ScanGeometry, ADoorFrameIsAnEdgeAndAGrazingWallSampledSparselyIsNot) {
  // The corridor's far wall points are metres apart (lone returns on one line): no edge.
  EXPECT_EQ(scan_geometry(corridor_points()).edges, 0u);
  // A door frame on the left wall: the wall ends at x = 1 and goes on 0.4 m farther back from x = 2.
  std::vector<Eigen::Vector2d> frame;
  for (int k = 0; k <= 20; ++k) frame.emplace_back(0.05 * k, 1.2);        // the wall up to the frame
  for (int k = 0; k <= 20; ++k) frame.emplace_back(2.0 + 0.05 * k, 1.6);  // the recess behind it
  EXPECT_EQ(scan_geometry(frame).edges, 1u);
  // The same wall with a gap (glass, a dropped stretch of beams) goes on along its line: no edge.
  std::vector<Eigen::Vector2d> gap;
  for (int k = 0; k <= 20; ++k) gap.emplace_back(0.05 * k, 1.2);
  for (int k = 0; k <= 20; ++k) gap.emplace_back(2.0 + 0.05 * k, 1.2);
  EXPECT_EQ(scan_geometry(gap).edges, 0u);
  // Behind up to eight lone returns (mixed pixels at the frame) it is still an edge.
  std::vector<Eigen::Vector2d> mixed = {frame.begin(), frame.begin() + 21};
  for (int k = 0; k < 4; ++k) mixed.emplace_back(1.2 + 0.2 * k, 1.2 + 3.0 * (k % 2) + 2.0);
  mixed.insert(mixed.end(), frame.begin() + 21, frame.end());
  EXPECT_EQ(scan_geometry(mixed).edges, 1u);
}

TEST(ScanGeometry, ItsOpenTranslationIsJudgedWhereTheSurfacesHoldTheScan) {
  // The corridor: its axis open (the far walls' lone dots are a tenth of the returns).
  const std::vector<Eigen::Vector2d> corridor = corridor_points();
  const ScanGeometry plain = scan_geometry(corridor);
  ASSERT_LT(4 * plain.lone_returns, plain.returns);
  const std::optional<Eigen::Vector2d> open = open_translation(plain, 0.01);
  ASSERT_TRUE(open.has_value());
  EXPECT_GT(std::abs(open->x()), 0.999);
  // A stretch of hedge and trunks beyond it, one return each: the hedge alone leaves its line
  // open, the trunks fix it, and lone returns are not taken for noise when they are most of the scan.
  std::vector<Eigen::Vector2d> hedge;
  for (int k = 0; k <= 10; ++k) hedge.emplace_back(-1.0 + 0.2 * k, 4.0);
  for (int k = 0; k < 12; ++k) hedge.emplace_back(8.0 + 1.5 * k, -6.0 + (k % 3) * 4.0);
  const ScanGeometry outdoors = scan_geometry(hedge);
  EXPECT_EQ(outdoors.lone_returns, 12u);
  EXPECT_EQ(outdoors.returns, 23u);
  EXPECT_FALSE(open_translation(outdoors, 0.01).has_value());
  hedge.resize(11 + 3);  // three trunks: a fifth of the returns, the hedge judged
  EXPECT_TRUE(open_translation(scan_geometry(hedge), 0.01).has_value());
}

}  // namespace
}  // namespace slam2d
