// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// False loop closures added to a pose graph, for judging robust back ends: the protocol of
// N. Sünderhauf and P. Protzel, "Switchable constraints for robust pose graph SLAM", IROS 2012
// (Vertigo's spoiled datasets), and of the comparisons after it (DCS, max-mixtures, PCM, GNC).
// Placements:
//  - random: two nodes anywhere in the graph (a place recognised wrongly across the map);
//  - local: the second node within local_span nodes of the first along the chain (a scan matched
//    to the wrong spot of the corridor it was just in: small errors, the hardest to tell);
//  - random-grouped / local-grouped: runs of group_size edges between consecutive nodes of the two
//    places, all with one measurement (a sequence matched to the wrong place, mutually consistent,
//    as a perceptual alias is).
// Each false edge measures a relative pose drawn uniformly (translation within +-max_translation
// on each axis, any heading) and carries the information of one of the graph's own loop edges
// drawn at random, so nothing but its disagreement with the rest tells it apart. Loop edges are the
// edges between nodes that are not consecutive. The false edges come after the graph's own, so
// that the edges from index `first_false` on are the outliers (precision and recall of a back end's
// choice are counted against them).

#include <array>
#include <cstddef>
#include <cstdint>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/optim/pose_graph.hpp"

namespace slam2d {

enum class FalseClosurePlacement { kRandom, kLocal, kRandomGrouped, kLocalGrouped };
constexpr auto choices(FalseClosurePlacement) {
  return std::array{Choice{"random", FalseClosurePlacement::kRandom}, Choice{"local", FalseClosurePlacement::kLocal},
                    Choice{"random-grouped", FalseClosurePlacement::kRandomGrouped},
                    Choice{"local-grouped", FalseClosurePlacement::kLocalGrouped}};
}

struct FalseClosureConfig {
  // The share of false edges among the loop edges afterwards: outliers / (outliers + loops).
  double share = 0.1;
  FalseClosurePlacement placement = FalseClosurePlacement::kRandom;
  int group_size = 10;            // edges per group (grouped placements)
  int local_span = 50;            // nodes: how far along the chain a local closure's second node lies
  double max_translation = 10.0;  // m: the false measurement's x and y within +-this
  std::uint64_t seed = 1;
};

template <typename Fields>
void describe(Fields& f, FalseClosureConfig& c) {
  f.number("share", c.share, "1", between(0, 0.95), "false edges among the loop edges afterwards");
  f.choice("placement", c.placement, "random, local, random-grouped or local-grouped");
  f.number("group_size", c.group_size, "edges", at_least(1), "consecutive false edges of a group");
  f.number("local_span", c.local_span, "nodes", at_least(2), "a local closure's second node within this many along the chain");
  f.number("max_translation", c.max_translation, "m", greater_than(0), "the false measurement's x and y within +-this");
  f.number("seed", c.seed, "1", any_value(), "of every random draw");
}

/// Throws Error for out-of-range values.
void validate(const FalseClosureConfig& config);

struct SpoiledGraph {
  PoseGraph graph;              // the input's edges, then the false ones
  std::size_t loop_edges = 0;   // the input's loop edges
  std::size_t first_false = 0;  // index of the first false edge (= the input's edge count)
  std::size_t false_edges = 0;
};

/// `graph` with false loop closures added. Throws Error for a graph with fewer than four nodes or
/// without loop edges (the share has nothing to count against), or one too short for a group.
SpoiledGraph add_false_loop_closures(const PoseGraph& graph, const FalseClosureConfig& config);

}  // namespace slam2d
