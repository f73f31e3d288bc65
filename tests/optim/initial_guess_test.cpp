// SPDX-License-Identifier: BSD-3-Clause
// The orientations-first start (optim/initial_guess.hpp): a consistent graph recovered exactly
// from every pose at the origin, headings across +-pi included; inconsistent turns averaged by
// their weights; nodes joined to nothing fixed left where they were.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "slam2d/core/rng.hpp"
#include "slam2d/optim/initial_guess.hpp"
#include "optim/pose_graph_fixture.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::make_edge;

// A symmetric positive definite information with correlations between all three coordinates.
Eigen::Matrix3d correlated_information(Rng& rng) {
  Eigen::Matrix3d A;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) A(r, c) = rng.uniform(-1.0, 1.0);
  }
  return A * A.transpose() + Eigen::Vector3d(50.0, 50.0, 200.0).asDiagonal().toDenseMatrix();
}

// Three laps of a rectangle whose third side faces +-pi, each edge measured without error.
TEST(OrientationsFirst, AConsistentGraphIsRecoveredExactlyFromTheOrigin) {
  Rng rng(7);
  std::vector<SE2> truth;
  for (int lap = 0; lap < 3; ++lap) {
    for (int s = 0; s < 24; ++s) {
      const double drift = 0.1 * lap;
      if (s < 8) truth.emplace_back(s + drift, drift, 0.02 * s);
      else if (s < 12) truth.emplace_back(8 + drift, s - 8 + drift, std::numbers::pi / 2);
      else if (s < 20) truth.emplace_back(8 - (s - 12) + drift, 4 + drift, std::numbers::pi - 0.01 * (s % 2));
      else truth.emplace_back(drift, 4 - (s - 20) + drift, -std::numbers::pi / 2 - 0.03);
    }
  }
  PoseGraph graph;
  graph.poses.assign(truth.size(), SE2());
  graph.poses[0] = truth[0];
  const auto add = [&](int from, int to) {
    graph.edges.push_back(make_edge(from, to, truth[from].between(truth[to]), correlated_information(rng)));
  };
  for (int k = 0; k + 1 < static_cast<int>(truth.size()); ++k) add(k, k + 1);
  for (int k = 24; k < static_cast<int>(truth.size()); k += 5) add(k - 24, k);
  const PoseGraph estimate = with_orientations_first_poses(graph);
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_TRUE(test::poses_near(estimate.poses[k], truth[k], 1e-9, 1e-9)) << k;
  }
  EXPECT_LT(chi2(estimate), 1e-15);
}

// Two measurements of one turn: their weighted mean (weights 1 and 3), also where they straddle pi.
TEST(OrientationsFirst, TurnsAreAveragedByTheirWeights) {
  const Eigen::Matrix3d one = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d three = Eigen::Vector3d(1.0, 1.0, 3.0).asDiagonal();
  PoseGraph graph;
  graph.poses.assign(2, SE2());
  graph.edges = {make_edge(0, 1, SE2(1, 0, 0.1), one), make_edge(0, 1, SE2(1, 0, 0.3), three)};
  EXPECT_NEAR(with_orientations_first_poses(graph).poses[1].theta(), 0.25, 1e-12);
  // pi - 0.1 and -pi + 0.1 (= pi + 0.1): pi, not 0.
  graph.edges = {make_edge(0, 1, SE2(1, 0, std::numbers::pi - 0.1), one),
                 make_edge(0, 1, SE2(1, 0, -std::numbers::pi + 0.1), one)};
  EXPECT_NEAR(std::abs(with_orientations_first_poses(graph).poses[1].theta()), std::numbers::pi, 1e-12);
  // Positions with the headings: node 1 one metre ahead of node 0 (which is fixed at the origin).
  EXPECT_NEAR(with_orientations_first_poses(graph).poses[1].x(), 1.0, 1e-12);
}

TEST(OrientationsFirst, NodesJoinedToNothingFixedKeepTheirPoses) {
  PoseGraph graph;
  graph.poses = {SE2(), SE2(5, 5, 1), SE2(7, 7, 2), SE2(9, 9, 3)};
  graph.edges = {make_edge(0, 1, SE2(1, 0, 0)), make_edge(2, 3, SE2(1, 0, 0))};
  const PoseGraph estimate = with_orientations_first_poses(graph);
  EXPECT_TRUE(test::poses_near(estimate.poses[1], SE2(1, 0, 0), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(estimate.poses[2], graph.poses[2], 0.0, 0.0));
  EXPECT_TRUE(test::poses_near(estimate.poses[3], graph.poses[3], 0.0, 0.0));
}

}  // namespace
}  // namespace slam2d
