// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A 2D pose graph: nodes are robot poses T_world_node, edges are measured relative poses with
// their information matrices (the constraints of graph SLAM; F. Lu, E. Milios, "Globally
// consistent range scan alignment for environment mapping", Autonomous Robots 4, 1997).
//
// The error of an edge is the g2o / SPA convention
//   e(X_i, X_j) = t2v(Z_ij^-1 (X_i^-1 X_j)),   chi2 = sum e^T Omega e,
// with t2v(T) = (x, y, theta) of T (translation, not the SE2 log): the figures other solvers
// report on the public benchmark graphs use it.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/pose_graph_file.hpp"

namespace slam2d {

struct PoseGraphEdge {
  int from = 0;  // node index
  int to = 0;    // node index
  SE2 T_from_to;  // measured pose of `to` in the frame of `from`
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();  // (x, y, theta), symmetric positive definite
  bool robust = false;  // the back end's robust kernel applies (loop closures); odometry edges stay quadratic
  bool closure = false;  // a loop closure (graph SLAM's; files do not carry it)
};

struct PoseGraph {
  std::vector<SE2> poses;            // T_world_node, by node index
  std::vector<PoseGraphEdge> edges;
  std::vector<bool> fixed;           // by node index; empty: node 0 is fixed (the gauge)

  std::size_t size() const { return poses.size(); }
  bool is_fixed(std::size_t node) const { return fixed.empty() ? node == 0 : fixed[node]; }
};

/// e = t2v(Z^-1 (X_from^-1 X_to)) and its analytic Jacobians with respect to the coordinates
/// (x, y, theta) of X_from and X_to (either may be null).
Eigen::Vector3d edge_error(const PoseGraphEdge& edge, const SE2& T_world_from, const SE2& T_world_to,
                           Eigen::Matrix3d* J_from = nullptr, Eigen::Matrix3d* J_to = nullptr);

/// The edge's squared Mahalanobis error e^T Omega e at the poses (no robust kernel).
double squared_error(const PoseGraphEdge& edge, const std::vector<SE2>& poses);

/// sum e^T Omega e over all edges (no robust kernel).
double chi2(const PoseGraph& graph);

/// The graph with each node's pose composed from a fixed node along a spanning tree of its edges
/// (Dijkstra) that takes as few loop edges as it can: the odometry chain (edges between
/// consecutive nodes) wherever it reaches, a loop edge only to bridge a break in it, so that one
/// false loop edge does not place the rest. Nodes no path joins to a fixed node keep their poses;
/// `reached`, if given, gets the flags of the others (fixed nodes included).
PoseGraph with_spanning_tree_poses(const PoseGraph& graph, std::vector<bool>* reached = nullptr);

/// Where an optimisation starts: the poses given (a file's vertices, a SLAM run's estimate), the
/// spanning tree's (above), the orientations-first estimate (optim/initial_guess.hpp), the one of
/// the given poses and the orientations-first estimate with the lower chi2 (kBetter), or both
/// (kBoth: optimised from each, sparse_pose_adjustment.hpp, the lower final chi2 kept). From
/// poses far from the optimum (all at the origin) Levenberg-Marquardt ends in a local minimum,
/// and from a drifted odometry it crawls (Vertigo's RingCity: 79 iterations, 10 from the
/// orientations-first start); but the given poses can lie in a better basin than any estimate
/// from the edges alone (hog-man's w10000: 171,545 against 336,204), and there the estimate's
/// chi2 is the higher (1.5e7 against 6.9e6), as it is the lower on every other graph measured
/// (docs/methods/sparse_pose_adjustment.md).
enum class InitialGuessChoice { kGiven, kSpanningTree, kOrientationsFirst, kBetter, kBoth };
constexpr auto choices(InitialGuessChoice) {
  return std::array{Choice{"given", InitialGuessChoice::kGiven}, Choice{"tree", InitialGuessChoice::kSpanningTree},
                    Choice{"orientations", InitialGuessChoice::kOrientationsFirst},
                    Choice{"better", InitialGuessChoice::kBetter}, Choice{"both", InitialGuessChoice::kBoth}};
}

/// Node indices in file order; FIX lines fix their nodes (else the first node is fixed). A file
/// with edges but no (or too few) vertices gets the missing initial poses by composing edges
/// outward from the known ones (along a spanning tree, as with_spanning_tree_poses). Throws Error
/// for an edge naming an unknown id that no edge connects, or a graph not connected to a fixed or
/// known node.
PoseGraph to_pose_graph(const PoseGraphFile& file);
/// The file back, with the ids of `original` (same node order), the poses of `graph`.
PoseGraphFile to_pose_graph_file(const PoseGraph& graph, const PoseGraphFile& original);
/// A g2o file for a graph built in memory: vertex ids are node indices.
PoseGraphFile to_pose_graph_file(const PoseGraph& graph);

}  // namespace slam2d
