// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Sparse Pose Adjustment: K. Konolige, G. Grisetti, R. Kuemmerle, W. Burgard, B. Limketkai,
// R. Vincent, "Efficient sparse pose adjustment for 2D mapping", IROS 2010.
//
// Levenberg-Marquardt over the pose graph (pose_graph.hpp): the analytic Jacobians of each edge
// are summed straight into the sparse normal matrix H (3x3 blocks, upper triangle, compressed
// column), the damped system (H + lambda diag(H)) dx = -b solved by sparse Cholesky (CHOLMOD,
// supernodal, fill-reducing ordering analysed once per graph structure and reused), poses updated
// by x <- x + dx on (x, y, theta) with the angle normalised. Fixed nodes are eliminated. Edges
// marked robust enter with IRLS weights of the configured kernel on sqrt(e^T Omega e); the
// truncated-least-squares kernel is reached by graduated non-convexity instead
// (graduated_non_convexity.hpp), as plain IRLS on it keeps whatever the start makes an inlier.
//
// Warm start: a SparsePoseAdjustment object keeps the symbolic factorisation while the node count
// and edge pattern are unchanged (only extended graphs re-analyse) and the last damping, so the
// optimisations after each loop closure of a SLAM run cost little.

#include <array>
#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

#include "slam2d/optim/graduated_non_convexity.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/optim/robust_kernel.hpp"

namespace slam2d {

struct SparsePoseAdjustmentConfig {
  int max_iterations = 100;
  double initial_lambda = 1e-4;
  double lambda_up = 10.0;
  double lambda_down = 0.1;
  double relative_tolerance = 1e-9;
  double step_tolerance = 1e-10;
  RobustKernel loop_kernel{};
  GraduatedNonConvexityConfig graduated{};
};

template <typename Fields>
void describe(Fields& f, SparsePoseAdjustmentConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "LM iterations (accepted plus rejected steps)");
  f.number("initial_lambda", c.initial_lambda, "1", greater_than(0), "damping of the first step, relative to diag(H)");
  f.number("lambda_up", c.lambda_up, "1", greater_than(1), "factor on a rejected step");
  f.number("lambda_down", c.lambda_down, "1", open_interval(0, 1), "factor on an accepted step");
  f.number("relative_tolerance", c.relative_tolerance, "1", at_least(0),
           "converged when a step changes the cost by less than this fraction (a rejected one too: rounding at the minimum)");
  f.number("step_tolerance", c.step_tolerance, "m and rad", at_least(0),
           "converged when a step moves no coordinate by more than this");
  f.section("loop_kernel", c.loop_kernel, "for edges with robust = true (none: plain least squares)");
  f.section("graduated", c.graduated, "graduated non-convexity, for loop_kernel.type tls");
}

struct SparsePoseAdjustmentResult {
  double initial_chi2 = 0.0;  // sum e^T Omega e before (no kernel)
  double final_chi2 = 0.0;    // ... after
  int iterations = 0;         // LM iterations run
  bool converged = false;     // the relative tolerance was met before max_iterations
  int rounds = 0;             // weight updates of graduated non-convexity (tls kernel; else 0)
  // Each edge's weight at the end, by edge index (1 for edges that are not robust): the kernel's
  // at the final residual, or the decision of graduated non-convexity (tls: 0 or 1). At least 0.5:
  // the back end keeps the edge; below, it rejects it (precision and recall of a robust back end).
  std::vector<double> edge_weights;
  double seconds = 0.0;       // wall time of the optimisation
};

/// Throws Error for out-of-range values.
void validate(const SparsePoseAdjustmentConfig& config);

/// An edge joined to a graph at its optimum, to first order: e^T (Omega^-1 + J H^-1 J^T)^-1 e, the
/// squared Mahalanobis distance of its error under its own covariance plus the poses' (H the
/// undamped Gauss-Newton matrix of the graph's edges, the loop kernel's weights in it), which is
/// the chi2 the optimum gains; and the largest move of a node the Gauss-Newton step would make.
struct PredictedJoin {
  double chi2 = 0.0;
  double max_translation = 0.0;  // m
  double max_turn = 0.0;         // rad
};

class SparsePoseAdjustment {
 public:
  explicit SparsePoseAdjustment(const SparsePoseAdjustmentConfig& config = {});
  ~SparsePoseAdjustment();
  SparsePoseAdjustment(SparsePoseAdjustment&&) noexcept;
  SparsePoseAdjustment& operator=(SparsePoseAdjustment&&) noexcept;

  /// Optimises graph.poses in place. Throws Error for an edge with an out-of-range node, a
  /// non-finite pose or measurement, or an information matrix that is not symmetric positive
  /// semi-definite.
  SparsePoseAdjustmentResult optimize(PoseGraph& graph);
  /// The same, converged at this relative tolerance instead of the configuration's (a SLAM run's
  /// optimisations between closures, whose poses only its front end reads). The tls kernel's
  /// graduated non-convexity keeps its own schedule.
  SparsePoseAdjustmentResult optimize(PoseGraph& graph, double relative_tolerance);

  /// For each candidate edge (not one of the graph's), what joining it alone would do at an
  /// optimum of the graph, to first order (PredictedJoin). Where the graph's Gauss-Newton matrix is
  /// singular, each edge's own e^T Omega e and no step. Throws Error as optimize() does, for the
  /// graph or a candidate.
  std::vector<PredictedJoin> predicted_joins(const PoseGraph& graph, const std::vector<PoseGraphEdge>& candidates);

  const SparsePoseAdjustmentConfig& config() const { return config_; }

 private:
  struct Solver;  // CHOLMOD state (common, symbolic factor, pattern)
  SparsePoseAdjustmentConfig config_;
  std::unique_ptr<Solver> solver_;
  double lambda_ = 0.0;  // the damping the last optimisation ended with
  std::vector<double> graduated_weights_;  // tls: the last optimisation's decisions, by edge
  std::vector<std::array<int, 2>> graduated_endpoints_;  // ... and those edges' nodes
};

/// One-shot optimisation (a fresh SparsePoseAdjustment).
SparsePoseAdjustmentResult optimize_pose_graph(PoseGraph& graph, const SparsePoseAdjustmentConfig& config = {});

/// An optimisation from the start `initial` chose (pose_graph.hpp).
struct StartedOptimization {
  SparsePoseAdjustmentResult result;  // of the run kept (its seconds: of both runs of kBoth)
  InitialGuessChoice start = InitialGuessChoice::kGiven;  // where the run kept started
  double given_chi2 = 0.0;  // of the poses given
  double estimate_chi2 = std::numeric_limits<double>::quiet_NaN();  // of the estimated start (kGiven: none)
};

/// One-shot optimisation from the given poses, an estimate from the edges (the spanning tree's or
/// the orientations-first one), the one of the given poses and the orientations-first estimate
/// with the lower chi2 (kBetter), or each of these two (kBoth: the lower final chi2 kept, the
/// given poses on a tie).
StartedOptimization optimize_pose_graph(PoseGraph& graph, const SparsePoseAdjustmentConfig& config,
                                        InitialGuessChoice initial);

}  // namespace slam2d
