// SPDX-License-Identifier: BSD-3-Clause
// The pose graph: the g2o edge error against its definition t2v(Z^-1 (X_i^-1 X_j)), its analytic
// Jacobians against central differences, and files turned into graphs and back (hand-written
// fixtures in both formats, edges-only files whose poses are composed along the edges).

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <string>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "optim/pose_graph_fixture.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::TempDir;

using test::make_edge;

SE2 random_pose(Rng& rng, double extent = 5.0) {
  return SE2(rng.uniform(-extent, extent), rng.uniform(-extent, extent), rng.uniform(-std::numbers::pi, std::numbers::pi));
}

// The definition, through the SE2 group operations.
Eigen::Vector3d reference_error(const PoseGraphEdge& edge, const SE2& from, const SE2& to) {
  return (edge.T_from_to.inverse() * from.between(to)).vector();
}

// d e / d (x, y, theta) of one pose by central differences (angle differences wrapped).
Eigen::Matrix3d numeric_jacobian(const PoseGraphEdge& edge, const SE2& from, const SE2& to, bool wrt_from) {
  constexpr double kStep = 1e-6;
  Eigen::Matrix3d J;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d delta = Eigen::Vector3d::Zero();
    delta(k) = kStep;
    const SE2& x = wrt_from ? from : to;
    const SE2 plus = SE2::from_vector(x.vector() + delta);
    const SE2 minus = SE2::from_vector(x.vector() - delta);
    const Eigen::Vector3d e_plus = wrt_from ? edge_error(edge, plus, to) : edge_error(edge, from, plus);
    const Eigen::Vector3d e_minus = wrt_from ? edge_error(edge, minus, to) : edge_error(edge, from, minus);
    J.col(k) = e_plus - e_minus;
    J(2, k) = angle_difference(e_plus.z(), e_minus.z());
    J.col(k) /= 2.0 * kStep;
  }
  return J;
}

TEST(PoseGraph, EdgeErrorIsTheRelativePoseInTheMeasurementFrame) {
  Rng rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const SE2 from = random_pose(rng);
    const SE2 to = random_pose(rng);
    const PoseGraphEdge edge = make_edge(0, 1, random_pose(rng, 2.0));
    const Eigen::Vector3d e = edge_error(edge, from, to);
    const Eigen::Vector3d expected = reference_error(edge, from, to);
    EXPECT_NEAR((e.head<2>() - expected.head<2>()).norm(), 0.0, 1e-12);
    EXPECT_NEAR(angle_difference(e.z(), expected.z()), 0.0, 1e-12);
    EXPECT_GE(e.z(), -std::numbers::pi);
    EXPECT_LT(e.z(), std::numbers::pi);
  }
  // A measurement equal to the relative pose gives zero error.
  const SE2 from(1.0, 2.0, 3.0), to(-4.0, 0.5, -2.9);
  const PoseGraphEdge exact = make_edge(0, 0, from.between(to));
  EXPECT_NEAR(edge_error(exact, from, to).norm(), 0.0, 1e-12);
}

TEST(PoseGraph, JacobiansMatchCentralDifferences) {
  Rng rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const SE2 from = random_pose(rng);
    const SE2 to = random_pose(rng);
    const PoseGraphEdge edge = make_edge(0, 0, random_pose(rng, 2.0));
    Eigen::Matrix3d J_from, J_to;
    edge_error(edge, from, to, &J_from, &J_to);
    EXPECT_TRUE(J_from.isApprox(numeric_jacobian(edge, from, to, true), 1e-6)) << J_from;
    EXPECT_TRUE(J_to.isApprox(numeric_jacobian(edge, from, to, false), 1e-6)) << J_to;
  }
  // Either Jacobian alone.
  const SE2 from(0.5, -1.0, 0.3), to(2.0, 1.0, -0.4);
  const PoseGraphEdge edge = make_edge(0, 0, SE2(1.0, 0.5, 0.1));
  Eigen::Matrix3d J_to;
  edge_error(edge, from, to, nullptr, &J_to);
  EXPECT_TRUE(J_to.isApprox(numeric_jacobian(edge, from, to, false), 1e-6));
}

TEST(PoseGraph, Chi2SumsTheWeightedSquaredErrors) {
  PoseGraph graph;
  graph.poses = {SE2(0, 0, 0), SE2(1, 0, 0), SE2(1, 1, 0)};
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  information.diagonal() << 4.0, 9.0, 100.0;
  graph.edges.push_back(make_edge(0, 1, SE2(1.5, 0, 0), information));  // e = (-0.5, 0, 0)
  graph.edges.push_back(make_edge(1, 2, SE2(0, 1, 0.1), information));  // e = (0, 0, -0.1)
  EXPECT_NEAR(chi2(graph), 4.0 * 0.25 + 100.0 * 0.01, 1e-12);
  graph.edges.push_back(make_edge(1, 3));
  EXPECT_THROW(chi2(graph), Error);
}

TEST(PoseGraph, FromTheG2oFixture) {
  const PoseGraph graph = to_pose_graph(read_pose_graph(test::fixture_path("graphs/small.g2o")));
  ASSERT_EQ(graph.size(), 3u);
  ASSERT_EQ(graph.edges.size(), 3u);
  EXPECT_EQ(graph.poses[1], SE2(1.0, 0.0, 0.5));
  EXPECT_EQ(graph.poses[2], SE2(1.5, 2.25, -1.0));
  ASSERT_EQ(graph.fixed.size(), 3u);
  EXPECT_TRUE(graph.is_fixed(0));
  EXPECT_FALSE(graph.is_fixed(1));
  EXPECT_EQ(graph.edges[2].from, 2);
  EXPECT_EQ(graph.edges[2].to, 0);
  EXPECT_EQ(graph.edges[0].information(1, 2), 23.0);
  EXPECT_EQ(graph.edges[0].information(2, 1), 23.0);
  EXPECT_FALSE(graph.edges[0].robust);
}

TEST(PoseGraph, TheToroFixtureIsTheSameGraph) {
  const PoseGraph g2o = to_pose_graph(read_pose_graph(test::fixture_path("graphs/small.g2o")));
  const PoseGraph toro = to_pose_graph(read_pose_graph(test::fixture_path("graphs/small.toro")));
  ASSERT_EQ(toro.size(), g2o.size());
  ASSERT_EQ(toro.edges.size(), g2o.edges.size());
  for (std::size_t k = 0; k < g2o.size(); ++k) EXPECT_EQ(toro.poses[k], g2o.poses[k]);
  for (std::size_t k = 0; k < g2o.edges.size(); ++k) {
    EXPECT_EQ(toro.edges[k].T_from_to, g2o.edges[k].T_from_to);
    EXPECT_EQ(toro.edges[k].information, g2o.edges[k].information);
  }
  EXPECT_TRUE(toro.fixed.empty());  // no FIX: node 0 is the gauge
  EXPECT_TRUE(toro.is_fixed(0));
  EXPECT_FALSE(toro.is_fixed(2));
  EXPECT_NEAR(chi2(toro), chi2(g2o), 1e-9);
}

TEST(PoseGraph, EdgesOnlyFilesComposePosesAlongTheEdges) {
  TempDir dir;
  const std::string path = dir.file("edges.g2o");
  std::ofstream(path) << "EDGE_SE2 10 11 1 0 1.5707963267948966 1 0 0 1 0 1\n"
                         "EDGE_SE2 12 11 0 -2 0 1 0 0 1 0 1\n"  // node 12 from node 11, backwards
                         "EDGE_SE2 11 12 5 5 0 1 0 0 1 0 1\n";  // a second edge, not used for the guess
  const PoseGraph graph = to_pose_graph(read_pose_graph(path));
  ASSERT_EQ(graph.size(), 3u);  // ids 10, 11, 12 in order of appearance
  EXPECT_TRUE(test::poses_near(graph.poses[0], SE2(), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(graph.poses[1], SE2(1, 0, std::numbers::pi / 2), 1e-12, 1e-12));
  // X_12 = X_11 (Z_12_11)^-1 = (1, 0, 90 deg) * (0, 2, 0) = (-1, 0, 90 deg).
  EXPECT_TRUE(test::poses_near(graph.poses[2], SE2(-1, 0, std::numbers::pi / 2), 1e-12, 1e-12));
  EXPECT_EQ(graph.edges[1].from, 2);
  EXPECT_EQ(graph.edges[1].to, 1);
  // The first two edges hold exactly.
  EXPECT_NEAR(edge_error(graph.edges[0], graph.poses[0], graph.poses[1]).norm(), 0.0, 1e-12);
  EXPECT_NEAR(edge_error(graph.edges[1], graph.poses[2], graph.poses[1]).norm(), 0.0, 1e-12);

  // Back to a file: the nodes get vertices with their ids.
  const PoseGraphFile file = to_pose_graph_file(graph, read_pose_graph(path));
  ASSERT_EQ(file.vertices.size(), 3u);
  EXPECT_EQ(file.vertices[2].id, 12);
  EXPECT_EQ(file.edges[1].from, 12);
  EXPECT_EQ(file.edges[1].to, 11);
}

// The start of an optimisation: the odometry chain composed from the fixed node, a loop edge (here
// a false one) only where the chain breaks, and a part no edge joins to a fixed node left alone.
TEST(PoseGraph, TheSpanningTreeFollowsTheOdometryChain) {
  PoseGraph graph;
  graph.poses.assign(7, SE2(9, 9, 1));  // a guess far from anything
  graph.poses[0] = SE2(1, 2, 0.5);      // the fixed node keeps its pose
  const SE2 step(1, 0, 0.1);
  for (int i = 0; i + 1 < 4; ++i) graph.edges.push_back(make_edge(i, i + 1, step));
  graph.edges.push_back(make_edge(0, 3, SE2(-5, 0, 0)));  // a false loop edge to a node the chain reaches
  graph.edges.push_back(make_edge(4, 1, SE2(0, 2, 0)));   // the only edge to node 4: it bridges a break
  graph.edges.push_back(make_edge(5, 6, step));           // nodes 5 and 6: joined to nothing fixed
  const PoseGraph tree = with_spanning_tree_poses(graph);
  SE2 expected = graph.poses[0];
  for (int i = 1; i < 4; ++i) {
    expected = expected * step;
    EXPECT_TRUE(test::poses_near(tree.poses[i], expected, 1e-12, 1e-12)) << i;
  }
  EXPECT_TRUE(test::poses_near(tree.poses[0], graph.poses[0], 0.0, 0.0));
  EXPECT_TRUE(test::poses_near(tree.poses[4], tree.poses[1] * SE2(0, 2, 0).inverse(), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(tree.poses[5], graph.poses[5], 0.0, 0.0));
  EXPECT_TRUE(test::poses_near(tree.poses[6], graph.poses[6], 0.0, 0.0));
  EXPECT_EQ(tree.edges.size(), graph.edges.size());
  // Every tree edge holds exactly; the false loop edge does not.
  for (const std::size_t k : {0u, 1u, 2u, 4u}) {
    EXPECT_NEAR(edge_error(tree.edges[k], tree.poses[tree.edges[k].from], tree.poses[tree.edges[k].to]).norm(), 0.0, 1e-12);
  }
  EXPECT_GT(edge_error(tree.edges[3], tree.poses[0], tree.poses[3]).norm(), 5.0);
}

TEST(PoseGraph, MissingVerticesGrowFromTheKnownOnes) {
  TempDir dir;
  const std::string path = dir.file("partial.graph");
  std::ofstream(path) << "VERTEX2 5 1 1 0\n"
                         "EDGE2 4 5 1 0 0 1 0 1 1 0 0\n"
                         "EDGE2 5 6 0 1 0 1 0 1 1 0 0\n";
  const PoseGraph graph = to_pose_graph(read_pose_graph(path));
  ASSERT_EQ(graph.size(), 3u);  // 5 (vertex), then 4 and 6
  EXPECT_TRUE(test::poses_near(graph.poses[0], SE2(1, 1, 0), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(graph.poses[1], SE2(0, 1, 0), 1e-12, 1e-12));
  EXPECT_TRUE(test::poses_near(graph.poses[2], SE2(1, 2, 0), 1e-12, 1e-12));
}

TEST(PoseGraph, UnreachableNodesAndUnknownFixIdsAreErrors) {
  TempDir dir;
  const std::string island = dir.file("island.g2o");
  std::ofstream(island) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n"
                           "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n"
                           "EDGE_SE2 7 8 1 0 0 1 0 0 1 0 1\n";
  EXPECT_THROW(to_pose_graph(read_pose_graph(island)), Error);
  const std::string fix = dir.file("fix.g2o");
  std::ofstream(fix) << "VERTEX_SE2 0 0 0 0\nFIX 3\n";
  EXPECT_THROW(to_pose_graph(read_pose_graph(fix)), Error);
}

TEST(PoseGraph, FileRoundTripKeepsIdsAndFixedNodes) {
  TempDir dir;
  const std::string path = dir.file("ids.g2o");
  std::ofstream(path) << "VERTEX_SE2 30 0 0 0\nVERTEX_SE2 10 1 0 0\nVERTEX_SE2 20 2 0 0\nFIX 10\n"
                         "EDGE_SE2 30 10 1 0 0 1 0 0 1 0 1\nEDGE_SE2 10 20 1 0 0 1 0 0 1 0 1\n";
  const PoseGraphFile original = read_pose_graph(path);
  PoseGraph graph = to_pose_graph(original);
  EXPECT_FALSE(graph.is_fixed(0));
  EXPECT_TRUE(graph.is_fixed(1));
  graph.poses[2] = SE2(2.5, 0.25, 0.125);
  write_g2o(dir.file("out.g2o"), to_pose_graph_file(graph, original));
  const PoseGraphFile back = read_pose_graph(dir.file("out.g2o"));
  ASSERT_EQ(back.vertices.size(), 3u);
  EXPECT_EQ(back.vertices[0].id, 30);
  EXPECT_EQ(back.vertices[2].id, 20);
  EXPECT_EQ(back.vertices[2].pose, SE2(2.5, 0.25, 0.125));
  EXPECT_EQ(back.fixed, std::vector<int>{10});
  EXPECT_EQ(back.edges[0].from, 30);

  PoseGraph grown = graph;
  grown.poses.push_back(SE2());
  EXPECT_THROW(to_pose_graph_file(grown, original), Error);
}

TEST(PoseGraph, InMemoryGraphsBecomeFilesWithIndexIds) {
  PoseGraph graph;
  graph.poses = {SE2(), SE2(1, 0, 0), SE2(2, 0, 0)};
  graph.fixed = {true, false, true};
  graph.edges.push_back(make_edge(0, 2, SE2(2, 0, 0)));
  const PoseGraphFile file = to_pose_graph_file(graph);
  ASSERT_EQ(file.vertices.size(), 3u);
  EXPECT_EQ(file.vertices[1].id, 1);
  EXPECT_EQ(file.fixed, (std::vector<int>{0, 2}));
  const PoseGraph back = to_pose_graph(file);
  EXPECT_EQ(back.fixed, graph.fixed);
  EXPECT_EQ(back.poses[2], graph.poses[2]);
}

}  // namespace
}  // namespace slam2d
