// SPDX-License-Identifier: BSD-3-Clause
// False loop closures (optim/false_loop_closures.hpp): how many, where each placement puts them,
// what they carry, the same graph from the same seed, and the graphs it refuses.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <set>

#include "slam2d/core/error.hpp"
#include "slam2d/optim/false_loop_closures.hpp"
#include "optim/pose_graph_fixture.hpp"

namespace slam2d {
namespace {

using test::make_edge;

// A chain of 200 nodes with 38 loop edges, each loop edge an information of its own.
PoseGraph chain_with_loops() {
  PoseGraph graph;
  graph.poses.assign(200, SE2());
  for (int i = 0; i + 1 < 200; ++i) graph.edges.push_back(make_edge(i, i + 1, SE2(1, 0, 0)));
  for (int i = 10; i < 200; i += 5) {
    graph.edges.push_back(make_edge(i - 10, i, SE2(10, 0, 0), (1.0 + i) * Eigen::Matrix3d::Identity()));
  }
  return graph;
}

TEST(FalseLoopClosures, TheShareCountsAgainstTheLoopEdgesAndTheGraphsOwnEdgesStay) {
  const PoseGraph graph = chain_with_loops();
  const std::size_t loops = 38;
  for (const double share : {0.1, 0.2, 0.5}) {
    const SpoiledGraph spoiled = add_false_loop_closures(graph, FalseClosureConfig{.share = share});
    EXPECT_EQ(spoiled.loop_edges, loops);
    EXPECT_EQ(spoiled.first_false, graph.edges.size());
    EXPECT_EQ(spoiled.false_edges, static_cast<std::size_t>(std::llround(share / (1.0 - share) * loops)));
    EXPECT_EQ(spoiled.graph.edges.size(), graph.edges.size() + spoiled.false_edges);
    EXPECT_NEAR(static_cast<double>(spoiled.false_edges) / static_cast<double>(spoiled.false_edges + loops), share, 0.02);
    for (std::size_t k = 0; k < graph.edges.size(); ++k) {
      EXPECT_EQ(spoiled.graph.edges[k].from, graph.edges[k].from);
      EXPECT_EQ(spoiled.graph.edges[k].T_from_to, graph.edges[k].T_from_to);
    }
    EXPECT_EQ(spoiled.graph.poses, graph.poses);
  }
  EXPECT_EQ(add_false_loop_closures(graph, FalseClosureConfig{.share = 0.0}).false_edges, 0u);
}

TEST(FalseLoopClosures, EachPlacementPutsThemWhereItSays) {
  const PoseGraph graph = chain_with_loops();
  std::set<double> loop_informations;
  for (const PoseGraphEdge& edge : graph.edges) {
    if (std::abs(edge.to - edge.from) > 1) loop_informations.insert(edge.information(0, 0));
  }
  for (const auto& [name, placement] : choices(FalseClosurePlacement{})) {
    const FalseClosureConfig config{.share = 0.5, .placement = placement, .group_size = 5, .local_span = 20};
    const SpoiledGraph spoiled = add_false_loop_closures(graph, config);
    const bool local = name.starts_with("local");
    const bool grouped = name.ends_with("grouped");
    bool far = false;  // a random placement reaches beyond local_span somewhere
    for (std::size_t k = spoiled.first_false; k < spoiled.graph.edges.size(); ++k) {
      const PoseGraphEdge& edge = spoiled.graph.edges[k];
      const int apart = std::abs(edge.to - edge.from);
      EXPECT_GT(apart, 1) << name;
      EXPECT_LT(std::max(edge.from, edge.to), 200) << name;
      if (local) {
        EXPECT_LE(apart, 20) << name;
      }
      far = far || apart > 20;
      EXPECT_LE(std::abs(edge.T_from_to.x()), config.max_translation) << name;
      EXPECT_EQ(loop_informations.count(edge.information(0, 0)), 1u) << name;  // a loop edge's own
      const std::size_t in_group = (k - spoiled.first_false) % 5;
      if (grouped && in_group > 0) {  // one measurement along consecutive nodes of both places
        const PoseGraphEdge& previous = spoiled.graph.edges[k - 1];
        EXPECT_EQ(edge.from, previous.from + 1) << name;
        EXPECT_EQ(edge.to, previous.to + 1) << name;
        EXPECT_EQ(edge.T_from_to, previous.T_from_to) << name;
      }
    }
    if (!local) {
      EXPECT_TRUE(far) << name;
    }
  }
}

TEST(FalseLoopClosures, TheSeedDecides) {
  const PoseGraph graph = chain_with_loops();
  const auto spoil = [&](std::uint64_t seed) {
    return add_false_loop_closures(graph, FalseClosureConfig{.share = 0.2, .seed = seed}).graph.edges;
  };
  const auto a = spoil(3);
  const auto b = spoil(3);
  const auto c = spoil(4);
  ASSERT_EQ(a.size(), b.size());
  bool differs = false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].from, b[k].from);
    EXPECT_EQ(a[k].to, b[k].to);
    EXPECT_EQ(a[k].T_from_to, b[k].T_from_to);
    differs = differs || !(a[k].T_from_to == c[k].T_from_to);
  }
  EXPECT_TRUE(differs);
}

TEST(FalseLoopClosures, GraphsWithoutLoopsOrRoomAreRefused) {
  PoseGraph chain;
  chain.poses.assign(10, SE2());
  for (int i = 0; i + 1 < 10; ++i) chain.edges.push_back(make_edge(i, i + 1, SE2(1, 0, 0)));
  EXPECT_THROW(add_false_loop_closures(chain, {}), Error);  // no loop edge to count against
  PoseGraph tiny;
  tiny.poses.assign(3, SE2());
  tiny.edges = {make_edge(0, 2)};
  EXPECT_THROW(add_false_loop_closures(tiny, {}), Error);
  const PoseGraph graph = chain_with_loops();
  EXPECT_THROW(add_false_loop_closures(graph, {.placement = FalseClosurePlacement::kRandomGrouped, .group_size = 199}), Error);
  EXPECT_THROW(add_false_loop_closures(graph, {.share = 0.99}), Error);
  EXPECT_THROW(add_false_loop_closures(graph, {.placement = FalseClosurePlacement::kLocal, .local_span = 500}), Error);
}

}  // namespace
}  // namespace slam2d
