// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/optim/initial_guess.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "slam2d/core/angles.hpp"

namespace slam2d {

namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// The unknowns: one per node that is neither fixed nor cut off from every fixed node.
struct Unknowns {
  std::vector<int> index;  // by node; -1: held at its pose
  int count = 0;
};

Unknowns unknowns(const PoseGraph& graph, const std::vector<bool>& reached) {
  Unknowns u;
  u.index.assign(graph.size(), -1);
  for (std::size_t node = 0; node < graph.size(); ++node) {
    if (reached[node] && !graph.is_fixed(node)) u.index[node] = u.count++;
  }
  return u;
}

// Solves the normal equations; nullopt where they are singular.
std::optional<Eigen::VectorXd> solve(int size, const Triplets& triplets, const Eigen::VectorXd& rhs) {
  Eigen::SparseMatrix<double> normal(size, size);
  normal.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  Eigen::VectorXd x = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !x.allFinite()) return std::nullopt;
  return x;
}

// Adds w (x_to - x_from - c)^2-type terms, blocks of size D, to the normal equations; an end held
// at its value goes to the right-hand side.
template <int D>
void add_difference(const Unknowns& u, int from, int to, const Eigen::Matrix<double, D, D>& W,
                    const Eigen::Matrix<double, D, 1>& c, const std::vector<Eigen::Matrix<double, D, 1>>& held,
                    Triplets& triplets, Eigen::VectorXd& rhs) {
  const int a = u.index[from];
  const int b = u.index[to];
  Eigen::Matrix<double, D, 1> known_b = W * c;  // to the right-hand side of `to`; its negative of `from`
  if (a < 0) known_b += W * held[from];
  if (b < 0) known_b -= W * held[to];
  for (int p = 0; p < D; ++p) {
    for (int q = 0; q < D; ++q) {
      if (a >= 0) triplets.emplace_back(D * a + p, D * a + q, W(p, q));
      if (b >= 0) triplets.emplace_back(D * b + p, D * b + q, W(p, q));
      if (a >= 0 && b >= 0) {
        triplets.emplace_back(D * a + p, D * b + q, -W(p, q));
        triplets.emplace_back(D * b + p, D * a + q, -W(p, q));
      }
    }
  }
  if (b >= 0) rhs.segment<D>(D * b) += known_b;
  if (a >= 0) rhs.segment<D>(D * a) -= known_b;
}

// The edge's covariance, or nullopt for an information matrix without an inverse.
std::optional<Eigen::Matrix3d> covariance(const Eigen::Matrix3d& information) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(information);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.vectorD().minCoeff() <= 0.0) return std::nullopt;
  return ldlt.solve(Eigen::Matrix3d::Identity());
}

}  // namespace

PoseGraph with_orientations_first_poses(const PoseGraph& graph) {
  std::vector<bool> reached;
  const PoseGraph tree = with_spanning_tree_poses(graph, &reached);
  const Unknowns u = unknowns(graph, reached);
  if (u.count == 0) return tree;

  // 1. Headings, each edge's turn regularised by the tree's multiple of 2 pi.
  std::vector<Eigen::Matrix<double, 1, 1>> heading(graph.size());
  for (std::size_t node = 0; node < graph.size(); ++node) heading[node](0) = tree.poses[node].theta();
  Triplets triplets;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(u.count);
  std::vector<std::optional<Eigen::Matrix3d>> covariances(graph.edges.size());
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    const PoseGraphEdge& edge = graph.edges[k];
    if (!reached[edge.from] || edge.from == edge.to) continue;
    covariances[k] = covariance(edge.information);
    const double weight = covariances[k] ? 1.0 / (*covariances[k])(2, 2) : edge.information(2, 2);
    if (!(weight > 0.0) || !std::isfinite(weight)) continue;
    const double turn = edge.T_from_to.theta();
    const double wraps = std::round((heading[edge.to](0) - heading[edge.from](0) - turn) / (2.0 * std::numbers::pi));
    add_difference<1>(u, edge.from, edge.to, Eigen::Matrix<double, 1, 1>(weight),
                      Eigen::Matrix<double, 1, 1>(turn + 2.0 * std::numbers::pi * wraps), heading, triplets, rhs);
  }
  const std::optional<Eigen::VectorXd> theta = solve(u.count, triplets, rhs);
  if (!theta) return tree;
  for (std::size_t node = 0; node < graph.size(); ++node) {
    if (u.index[node] >= 0) heading[node](0) = (*theta)(u.index[node]);
  }

  // 2. Positions: t_to - t_from = R_from t_measured, weighed by the translation's information in
  //    the world frame (the marginal of its covariance).
  std::vector<Eigen::Vector2d> position(graph.size());
  for (std::size_t node = 0; node < graph.size(); ++node) position[node] = tree.poses[node].translation();
  triplets.clear();
  rhs = Eigen::VectorXd::Zero(2 * u.count);
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    const PoseGraphEdge& edge = graph.edges[k];
    if (!reached[edge.from] || edge.from == edge.to) continue;
    // e_t = R_z^T (R_from^T (t_to - t_from) - t_z) = (R_from R_z)^T (t_to - t_from - R_from t_z).
    const Eigen::Matrix2d R_from = Eigen::Rotation2Dd(heading[edge.from](0)).toRotationMatrix();
    const Eigen::Matrix2d R = R_from * edge.T_from_to.rotation();
    Eigen::Matrix2d information_xy = edge.information.topLeftCorner<2, 2>();
    if (covariances[k]) information_xy = covariances[k]->topLeftCorner<2, 2>().inverse();
    const Eigen::Matrix2d W = R * information_xy * R.transpose();
    if (!W.allFinite()) continue;
    add_difference<2>(u, edge.from, edge.to, W, Eigen::Vector2d(R_from * edge.T_from_to.translation()), position,
                      triplets, rhs);
  }
  const std::optional<Eigen::VectorXd> xy = solve(2 * u.count, triplets, rhs);
  if (!xy) return tree;
  PoseGraph estimate = graph;
  for (std::size_t node = 0; node < graph.size(); ++node) {
    const int i = u.index[node];
    if (i >= 0) estimate.poses[node] = SE2((*xy)(2 * i), (*xy)(2 * i + 1), normalize_angle(heading[node](0)));
  }
  return estimate;
}

}  // namespace slam2d
