// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/optim/false_loop_closures.hpp"

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"

namespace slam2d {

namespace {

bool is_loop(const PoseGraphEdge& edge) { return std::abs(edge.to - edge.from) > 1; }

bool grouped(FalseClosurePlacement placement) {
  return placement == FalseClosurePlacement::kRandomGrouped || placement == FalseClosurePlacement::kLocalGrouped;
}

bool local(FalseClosurePlacement placement) {
  return placement == FalseClosurePlacement::kLocal || placement == FalseClosurePlacement::kLocalGrouped;
}

// The first nodes of the two places: `from` anywhere a group fits, `to` anywhere else (random) or
// within local_span of it (local), never a neighbour of it, the group fitting too.
std::pair<int, int> places(int nodes, int group, const FalseClosureConfig& config, Rng& rng) {
  const int starts = nodes - group + 1;  // first nodes a group fits after
  for (;;) {
    const int from = static_cast<int>(rng.uniform_index(static_cast<std::size_t>(starts)));
    int to = 0;
    if (local(config.placement)) {
      const int span = config.local_span;
      const int offset = 2 + static_cast<int>(rng.uniform_index(static_cast<std::size_t>(span - 1)));  // 2..span
      to = rng.bernoulli(0.5) ? from + offset : from - offset;
    } else {
      to = static_cast<int>(rng.uniform_index(static_cast<std::size_t>(starts)));
    }
    if (to >= 0 && to < starts && std::abs(to - from) > 1) return {from, to};
  }
}

}  // namespace

void validate(const FalseClosureConfig& config) { check_fields(config, "FalseClosureConfig"); }

SpoiledGraph add_false_loop_closures(const PoseGraph& graph, const FalseClosureConfig& config) {
  validate(config);
  const int nodes = static_cast<int>(graph.size());
  check(nodes >= 4, "false loop closures: the graph has " + std::to_string(nodes) + " nodes, at least 4 are needed");
  std::vector<std::size_t> loops;
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    if (is_loop(graph.edges[k])) loops.push_back(k);
  }
  check(!loops.empty(), "false loop closures: the graph has no loop edges (edges between nodes that are not "
                        "consecutive) for the share to count against");
  const int group = grouped(config.placement) ? config.group_size : 1;
  check(group + 2 <= nodes, "false loop closures: a group of " + std::to_string(group) + " does not fit in " +
                                std::to_string(nodes) + " nodes");
  if (local(config.placement)) {
    check(config.local_span + group <= nodes, "false loop closures: local_span " + std::to_string(config.local_span) +
                                                  " is longer than the graph allows");
  }
  SpoiledGraph spoiled{.graph = graph, .loop_edges = loops.size(), .first_false = graph.edges.size()};
  const double wanted = config.share / (1.0 - config.share) * static_cast<double>(loops.size());
  const auto count = static_cast<std::size_t>(std::llround(wanted));
  Rng rng(config.seed);
  while (spoiled.false_edges < count) {
    const auto [from, to] = places(nodes, group, config, rng);
    const double x = rng.uniform(-config.max_translation, config.max_translation);
    const double y = rng.uniform(-config.max_translation, config.max_translation);
    const double theta = rng.uniform(-std::numbers::pi, std::numbers::pi);
    const Eigen::Matrix3d& information = graph.edges[loops[rng.uniform_index(loops.size())]].information;
    for (int k = 0; k < group && spoiled.false_edges < count; ++k) {
      spoiled.graph.edges.push_back(
          PoseGraphEdge{.from = from + k, .to = to + k, .T_from_to = SE2(x, y, theta), .information = information});
      ++spoiled.false_edges;
    }
  }
  return spoiled;
}

}  // namespace slam2d
