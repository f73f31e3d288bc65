// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Graduated non-convexity with the truncated-least-squares cost: H. Yang, P. Antonante,
// V. Tzoumas, L. Carlone, "Graduated non-convexity for robust spatial perception: from non-minimal
// solvers to global outlier rejection", IEEE Robotics and Automation Letters 5(2), 2020.
//
// The robust edges (loop closures) cost min(r^2, c^2), r^2 = e^T Omega e: an edge further than c
// from the rest costs the same however far it is, so it has no pull. That cost has a local
// minimum wherever a set of edges is dropped; GNC reaches a good one by a surrogate with a control
// parameter mu, least squares as mu -> 0 and the truncated cost as mu -> infinity (Sec. III), and
// alternates (Black-Rangarajan duality, Sec. IV):
//  1. the weighted least squares with every weight fixed (Levenberg-Marquardt,
//     sparse_pose_adjustment.hpp);
//  2. each robust edge's weight, the surrogate's optimum at its residual (Eq. (14)):
//       w = 1                                  r^2 <= mu / (mu + 1) c^2
//       w = c / r sqrt(mu (mu + 1)) - mu        in between
//       w = 0                                  r^2 >= (mu + 1) / mu c^2
//  3. mu <- mu_factor mu.
// It starts from the least squares over every edge, mu = c^2 / (2 max r^2 - c^2) (Remark 5), and
// stops when every weight is 0 or 1 (the truncated cost's own decision: each edge kept or dropped),
// then solves the kept edges to convergence. An edge of weight 0 leaves the system, so the fill-in
// of far false closures costs only the first rounds.

#include <vector>

#include "slam2d/core/config_fields.hpp"

namespace slam2d {

struct PoseGraph;
struct SparsePoseAdjustmentConfig;
struct SparsePoseAdjustmentResult;

struct GraduatedNonConvexityConfig {
  double mu_factor = 1.4;     // the paper's
  int max_rounds = 1000;      // weight updates at most (mu grows 1.4^1000: never the limit in practice)
  int round_iterations = 10;  // LM iterations of each weighted least squares but the last
};

template <typename Fields>
void describe(Fields& f, GraduatedNonConvexityConfig& c) {
  f.number("mu_factor", c.mu_factor, "1", greater_than(1), "mu grows by this factor each round (Yang et al.: 1.4)");
  f.number("max_rounds", c.max_rounds, "1", at_least(1), "weight updates at most");
  f.number("round_iterations", c.round_iterations, "1", at_least(1),
           "LM iterations of each round's weighted least squares (the last, on the kept edges: max_iterations)");
}

/// The weight of Eq. (14) for a residual r^2 = e^T Omega e, threshold c^2, control parameter mu.
double truncated_least_squares_weight(double r2, double c2, double mu);

/// Optimises graph.poses in place: GNC over the truncated-least-squares cost of the robust edges,
/// c = config.loop_kernel.scale, each weighted least squares by Levenberg-Marquardt with config's
/// settings. The result counts the LM iterations of every round (`rounds`: the weight updates).
/// `previous_weights`, the edge_weights of the last optimisation of this graph before edges were
/// appended (an incremental SLAM back end), are tried first: kept where the solution with them
/// agrees with each (kept edges within c, dropped ones beyond), a fresh GNC otherwise.
SparsePoseAdjustmentResult optimize_graduated(PoseGraph& graph, const SparsePoseAdjustmentConfig& config,
                                              const std::vector<double>& previous_weights = {});

}  // namespace slam2d
