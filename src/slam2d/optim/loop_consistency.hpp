// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Pairwise consistency of loop closures (J. G. Mangelson, D. Dominic, R. M. Eustice,
// R. Vasudevan, "Pairwise consistent measurement set maximization for robust multi-robot map
// merging", ICRA 2018), as a gate before the back end.
//
// Two loop edges z_ij and z_kl whose ends lie near each other along the odometry chain (|i - k| and
// |j - l| within `window` nodes) close a cycle with two short stretches of the chain:
//     E = z_ij  C_jl  z_kl^-1  C_ki   (C_ab: the chain's composed edges from node a to node b),
// which is the identity if both closures are true. Its covariance is the four measurements'
// propagated to the cycle's start (first order, each as a left perturbation carried by the adjoint
// of the product before it); the chain's stretch from prefix sums of its edges' covariances moved
// to the world frame of the dead-reckoned chain (O(1) a pair). The pair is consistent when
// log(E)^T Sigma_E^-1 log(E) is within chi-square's 99.9 % quantile with 3 degrees of freedom.
//
// A closure consistent with at least `min_support` others near it is supported: a place recognised
// along a stretch of travel, as true revisits are. A closure with no partner near it is lone; a pair
// of far ends tests nothing (the chain's covariance over thousands of nodes admits anything), so a
// lone closure is judged against the optimum of the supported ones instead (optimize_gated). A
// closure placed at random across the map has no consistent partner near it and no agreement with
// that optimum, so it never reaches the sparse factor, where least squares over random edges fills
// the factor in.

#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/optim/sparse_pose_adjustment.hpp"

namespace slam2d {

struct LoopConsistencyConfig {
  bool enabled = true;
  int window = 3;               // nodes along the chain two closures' ends may lie apart to be compared
  int wide_window = 30;         // the same, for the support that lets a closure take the covariance test
  int min_support = 1;          // consistent partners that make a closure supported
  double gate_z = 3.09;         // the pairs' chi-square gate's level (99.9 %, 3 degrees of freedom: 16.3)
  double admission_z = 5.0;     // the admission's (a closure judged against the optimum: one in 3.5 million refused by chance)
  int max_admission_rounds = 10;  // optimisations that admit the closures agreeing with the last
  int max_covariance_tests = 500;   // closures beyond the gate tested with the poses' covariance, per round
  double max_predicted_turn = 0.25;  // rad: that test is first order, trusted where joining turns no node further
  double max_lone_turn = 0.05;       // rad: the same for a closure with no partner within wide_window
  RobustKernel kernel{.type = RobustKernelType::kTls, .scale = 2.0};  // on the supported closures
};

template <typename Fields>
void describe(Fields& f, LoopConsistencyConfig& c) {
  f.flag("enabled", c.enabled, "gate the loop edges by pairwise consistency before the back end");
  f.number("window", c.window, "nodes", at_least(1), "two closures are compared when both their ends lie within this many nodes along the chain");
  f.number("wide_window", c.wide_window, "nodes", at_least(1),
           "a closure with no consistent partner this near is lone: the covariance test admits it for small corrections only (max_lone_turn)");
  f.number("min_support", c.min_support, "1", at_least(1), "consistent partners that make a closure supported");
  f.number("max_admission_rounds", c.max_admission_rounds, "1", at_least(0),
           "optimisations after the first that admit the closures agreeing with the last optimum");
  f.number("max_covariance_tests", c.max_covariance_tests, "1", at_least(0),
           "closures beyond the gate at an optimum tested with the poses' covariance, per round (the likeliest first)");
  f.number("max_predicted_turn", c.max_predicted_turn, "rad", greater_than(0),
           "the covariance test is first order: trusted where the step that joins the closure turns no node further");
  f.number("max_lone_turn", c.max_lone_turn, "rad", greater_than(0),
           "max_predicted_turn for a lone closure: it makes small corrections only, a large one waits for support");
  f.section("kernel", c.kernel, "on the supported closures, whose optimum decides which closures agree (tls: by graduated non-convexity)");
  f.number("gate_z", c.gate_z, "1", greater_than(0), "normal quantile of the pairs' chi-square gate (3.09: 99.9 %)");
  f.number("admission_z", c.admission_z, "1", greater_than(0),
           "normal quantile of the admission's chi-square gate at the optimum (5: tested on every closure of a graph, one in 3.5 million true ones refused)");
}

/// Throws Error for out-of-range values.
void validate(const LoopConsistencyConfig& config);

/// Each robust edge's support: how many robust edges near it along the chain it is consistent with
/// (by edge index; 0 for edges that are not robust, and for robust edges whose cycles cross a break
/// in the chain of edges between consecutive nodes, which cannot be tested).
struct LoopSupport {
  std::vector<int> partners;
  std::size_t pairs_tested = 0;
  std::size_t pairs_consistent = 0;
};

LoopSupport loop_support(const PoseGraph& graph, const LoopConsistencyConfig& config);

/// The cycle's squared Mahalanobis distance of two loop edges (indices into graph.edges) with the
/// chain between their ends (infinity where the chain is broken): the pairwise test, exposed for
/// the tests and the brute force they compare with.
double cycle_distance2(const PoseGraph& graph, std::size_t first, std::size_t second);

struct GatedOptimization {
  StartedOptimization optimization;  // its edge_weights by the input's edge index (refused: 0)
  std::size_t loop_edges = 0;
  std::size_t supported = 0;         // by their pairs (or bridging a break in the chain)
  std::size_t admitted = 0;          // within the gate at the last optimum: the closures kept
  std::size_t refused = 0;           // beyond it
  int admission_rounds = 0;          // optimisations of the admitted closures
  std::size_t covariance_tests = 0;  // closures tested with the poses' covariance
  bool decided = false;              // the closures admitted disagreed: the membership kernel chose among them
};

/// Optimises graph.poses in place with the gate:
///  1. every edge that is not robust and the supported loop edges, from `initial`, with the gate's
///     kernel (GNC over the truncated cost by default: a consistent group of false closures, a
///     perceptual alias, is supported too);
///  2. every loop edge within the chi-square gate at that optimum, optimised with `config`'s own
///     kernel from there, again until the admitted set stands (max_admission_rounds).
/// On a graph of true closures each lies within the gate at the optimum, so the result is the plain
/// optimum; a closure that disagrees with the consistent ones never reaches the factor. The
/// refused edges stay in `graph` (their weight 0 in the result). Disabled: optimize_pose_graph.
GatedOptimization optimize_gated(PoseGraph& graph, const SparsePoseAdjustmentConfig& config, InitialGuessChoice initial,
                                 const LoopConsistencyConfig& gate);

}  // namespace slam2d
