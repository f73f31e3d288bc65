// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/optim/loop_consistency.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <unordered_map>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

using Eigen::Matrix3d;

Matrix3d carried(const SE2& T, const Matrix3d& covariance) {
  const Matrix3d ad = T.adjoint();
  return ad * covariance * ad.transpose();
}

// An edge's covariance as a right perturbation of its measurement (g2o's error is taken in the
// `to` frame); an information that cannot be inverted carries nothing (unknown_covariance).
Matrix3d edge_covariance(const PoseGraphEdge& edge) {
  const Eigen::LDLT<Matrix3d> ldlt(edge.information);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.vectorD().minCoeff() <= 0.0) return unknown_covariance();
  return ldlt.solve(Matrix3d::Identity());
}

bool is_chain_edge(const PoseGraphEdge& edge) { return !edge.robust && std::abs(edge.to - edge.from) == 1; }

// The odometry chain (the edges between consecutive nodes that are not robust), dead-reckoned:
// poses D_n from node 0, and S_n, the sum over its first n edges of each edge's covariance moved
// to the world frame at the edge's end (a left perturbation of D_n with D_0 held).
class Chain {
 public:
  explicit Chain(const PoseGraph& graph) : poses_(graph.size()), sums_(graph.size(), Matrix3d::Zero()), breaks_(graph.size(), 0) {
    std::vector<const PoseGraphEdge*> links(graph.size(), nullptr);
    for (const PoseGraphEdge& edge : graph.edges) {
      if (!is_chain_edge(edge)) continue;
      const std::size_t n = static_cast<std::size_t>(std::min(edge.from, edge.to));
      if (n + 1 < graph.size() && !links[n]) links[n] = &edge;
    }
    for (std::size_t n = 0; n + 1 < graph.size(); ++n) {
      if (!links[n]) {  // a break: the stretches across it are not measured
        poses_[n + 1] = poses_[n];
        sums_[n + 1] = sums_[n];
        breaks_[n + 1] = breaks_[n] + 1;
        continue;
      }
      const PoseGraphEdge& edge = *links[n];
      const bool forward = edge.from == static_cast<int>(n);
      const SE2 step = forward ? edge.T_from_to : edge.T_from_to.inverse();
      // (Z exp(d))^-1 = Z^-1 exp(-Ad(Z) d): a reversed edge's right perturbation through Ad(Z).
      const Matrix3d covariance = forward ? edge_covariance(edge) : carried(edge.T_from_to, edge_covariance(edge));
      poses_[n + 1] = poses_[n] * step;
      sums_[n + 1] = sums_[n] + carried(poses_[n + 1], covariance);
      breaks_[n + 1] = breaks_[n];
    }
  }

  bool joins(int a, int b) const { return breaks_[static_cast<std::size_t>(a)] == breaks_[static_cast<std::size_t>(b)]; }

  // C_ab = D_a^-1 D_b, forwards or backwards along the chain.
  SE2 stretch(int a, int b) const { return pose(a).between(pose(b)); }

  // C_ab's covariance as a left perturbation in a's frame: Ad(D_a)^-1 |S_b - S_a| Ad(D_a)^-T
  // (backwards, the inverse of the forward stretch b..a, whose right perturbation at a is the same).
  Matrix3d stretch_covariance(int a, int b) const {
    const Matrix3d between = b >= a ? sum(b) - sum(a) : sum(a) - sum(b);
    return carried(pose(a).inverse(), between);
  }

 private:
  const SE2& pose(int n) const { return poses_[static_cast<std::size_t>(n)]; }
  const Matrix3d& sum(int n) const { return sums_[static_cast<std::size_t>(n)]; }

  std::vector<SE2> poses_;
  std::vector<Matrix3d> sums_;
  std::vector<int> breaks_;  // missing chain edges before each node
};

// A loop edge oriented from its lower node to its higher one, with its covariance (right perturbation).
struct Closure {
  int from = 0, to = 0;
  SE2 T_from_to;
  Matrix3d covariance = Matrix3d::Identity();
};

Closure closure_of(const PoseGraphEdge& edge) {
  if (edge.from <= edge.to) return {edge.from, edge.to, edge.T_from_to, edge_covariance(edge)};
  return {edge.to, edge.from, edge.T_from_to.inverse(), carried(edge.T_from_to, edge_covariance(edge))};
}

// The cycle z_ij C_jl z_kl^-1 C_ki (header): each factor's noise as a left perturbation, carried to
// the cycle's start by the adjoint of the product before it.
double cycle_distance2(const Chain& chain, const Closure& a, const Closure& b) {
  if (!chain.joins(a.to, b.to) || !chain.joins(b.from, a.from)) return std::numeric_limits<double>::infinity();
  const SE2& z1 = a.T_from_to;
  Matrix3d covariance = carried(z1, a.covariance);  // (z exp(d)) = exp(Ad(z) d) z
  covariance += carried(z1, chain.stretch_covariance(a.to, b.to));
  const SE2 p2 = z1 * chain.stretch(a.to, b.to);
  covariance += carried(p2, b.covariance);  // (z exp(d))^-1 = exp(-d) z^-1
  const SE2 p3 = p2 * b.T_from_to.inverse();
  covariance += carried(p3, chain.stretch_covariance(b.from, a.from));
  const Eigen::Vector3d xi = (p3 * chain.stretch(b.from, a.from)).log();
  const Eigen::LDLT<Matrix3d> ldlt(covariance);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::numeric_limits<double>::infinity();
  return xi.dot(ldlt.solve(xi));
}

void check_nodes(const PoseGraph& graph) {
  const int nodes = static_cast<int>(graph.size());
  for (const PoseGraphEdge& edge : graph.edges) {
    check(edge.from >= 0 && edge.to >= 0 && edge.from < nodes && edge.to < nodes,
          "loop consistency: an edge names node " + std::to_string(std::max(edge.from, edge.to)) + " of a graph of " +
              std::to_string(nodes) + " nodes");
  }
}

std::uint64_t bucket_key(int from_bucket, int to_bucket) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(from_bucket)) << 32) | static_cast<std::uint32_t>(to_bucket);
}

}  // namespace

void validate(const LoopConsistencyConfig& config) { check_fields(config, "LoopConsistencyConfig"); }

double cycle_distance2(const PoseGraph& graph, std::size_t first, std::size_t second) {
  check(first < graph.edges.size() && second < graph.edges.size(), "cycle_distance2: edge index out of range");
  check_nodes(graph);
  const Chain chain(graph);
  return cycle_distance2(chain, closure_of(graph.edges[first]), closure_of(graph.edges[second]));
}

LoopSupport loop_support(const PoseGraph& graph, const LoopConsistencyConfig& config) {
  validate(config);
  check_nodes(graph);
  LoopSupport support;
  support.partners.assign(graph.edges.size(), 0);
  const Chain chain(graph);
  std::vector<Closure> closures(graph.edges.size());
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> buckets;
  const int w = config.window;
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    if (!graph.edges[k].robust) continue;
    closures[k] = closure_of(graph.edges[k]);
    buckets[bucket_key(closures[k].from / w, closures[k].to / w)].push_back(k);
  }
  const double gate = chi_square_quantile(3.0, config.gate_z);
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    if (!graph.edges[k].robust) continue;
    const Closure& a = closures[k];
    int& partners = support.partners[k];
    for (int df = -1; df <= 1 && partners < config.min_support; ++df) {
      for (int dt = -1; dt <= 1 && partners < config.min_support; ++dt) {
        const auto bucket = buckets.find(bucket_key(a.from / w + df, a.to / w + dt));
        if (bucket == buckets.end()) continue;
        for (const std::size_t m : bucket->second) {
          const Closure& b = closures[m];
          if (m == k || std::abs(a.from - b.from) > w || std::abs(a.to - b.to) > w) continue;
          ++support.pairs_tested;
          if (cycle_distance2(chain, a, b) > gate) continue;
          ++support.pairs_consistent;
          if (++partners >= config.min_support) break;
        }
      }
    }
  }
  return support;
}

namespace {

// The edges of `graph` taken by `take`, at `poses`; `index` gets each one's input index.
PoseGraph edges_taken(const PoseGraph& graph, const std::vector<char>& take, std::vector<SE2> poses,
                      std::vector<std::size_t>& index) {
  PoseGraph taken{.poses = std::move(poses), .edges = {}, .fixed = graph.fixed};
  index.clear();
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    if (!take[k]) continue;
    taken.edges.push_back(graph.edges[k]);
    index.push_back(k);
  }
  return taken;
}

bool any_closure_beyond(const PoseGraph& graph, double gate2) {
  return std::any_of(graph.edges.begin(), graph.edges.end(),
                     [&](const PoseGraphEdge& edge) { return edge.robust && squared_error(edge, graph.poses) > gate2; });
}

// `total` followed by `next`: its end state, the work of both.
void add_result(SparsePoseAdjustmentResult& total, const SparsePoseAdjustmentResult& next) {
  total.final_chi2 = next.final_chi2;
  total.converged = next.converged;
  total.edge_weights = next.edge_weights;
  total.iterations += next.iterations;
  total.rounds += next.rounds;
  total.seconds += next.seconds;
}

}  // namespace

GatedOptimization optimize_gated(PoseGraph& graph, const SparsePoseAdjustmentConfig& config, InitialGuessChoice initial,
                                 const LoopConsistencyConfig& gate) {
  GatedOptimization gated;
  for (const PoseGraphEdge& edge : graph.edges) gated.loop_edges += edge.robust ? 1 : 0;
  if (!gate.enabled) {
    gated.optimization = optimize_pose_graph(graph, config, initial);
    gated.supported = gated.admitted = gated.loop_edges;
    return gated;
  }
  const LoopSupport support = loop_support(graph, gate);
  LoopConsistencyConfig wide = gate;
  wide.window = gate.wide_window;
  const LoopSupport wide_support = loop_support(graph, wide);
  const Chain chain(graph);
  const double gate2 = chi_square_quantile(3.0, gate.admission_z);
  SparsePoseAdjustmentConfig membership = config;
  membership.loop_kernel = gate.kernel;

  // 1. The edges that are not robust, the supported closures and those that bridge a break in the
  //    chain (without them the graph falls apart). Least squares first; where a supported closure
  //    then lies beyond the gate (a consistent group of false ones, a perceptual alias, is
  //    supported too), the membership kernel decides from the start again.
  std::vector<char> admitted(graph.edges.size(), 0);
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    const PoseGraphEdge& edge = graph.edges[k];
    admitted[k] = !edge.robust || !chain.joins(edge.from, edge.to) || support.partners[k] >= gate.min_support;
    gated.supported += edge.robust && admitted[k] ? 1 : 0;
  }
  std::vector<std::size_t> index;  // kept edge -> input edge
  PoseGraph kept = edges_taken(graph, admitted, graph.poses, index);
  gated.optimization = optimize_pose_graph(kept, config, initial);
  std::vector<char> dropped(graph.edges.size(), 0);  // supported, refused by the membership kernel
  if (any_closure_beyond(kept, gate2) && membership.loop_kernel.type != config.loop_kernel.type) {
    kept.poses = graph.poses;
    gated.optimization = optimize_pose_graph(kept, membership, initial);
    for (std::size_t m = 0; m < index.size(); ++m) {
      dropped[index[m]] = gated.optimization.result.edge_weights[m] < 0.5;
      admitted[index[m]] = !dropped[index[m]];
    }
  }

  // 2. The closures kept, optimised with the configured kernel; then every closure left out whose
  //    error there is within the gate, and every one not dropped above whose error is within the
  //    gate under its own covariance plus the poses' (the chi2 it would add: a closure the optimum
  //    never moved towards is judged with the optimum's uncertainty) where joining it turns no node
  //    by more than max_predicted_turn (the test is first order), or, a closure with no partner even
  //    within wide_window, by more than max_lone_turn (a lone closure makes small corrections only;
  //    a large one waits for support); again, until none joins.
  SparsePoseAdjustment spa(config);
  for (int round = 0;; ++round) {
    kept = edges_taken(graph, admitted, std::move(kept.poses), index);
    add_result(gated.optimization.result, spa.optimize(kept));
    ++gated.admission_rounds;
    if (round == gate.max_admission_rounds) break;

    bool joined = false;
    std::vector<std::pair<double, std::size_t>> doubtful;  // (e^T Omega e, edge) beyond the gate
    for (std::size_t k = 0; k < graph.edges.size(); ++k) {
      if (admitted[k]) continue;
      const double r2 = squared_error(graph.edges[k], kept.poses);
      if (r2 <= gate2) {
        admitted[k] = joined = true;
      } else if (!dropped[k]) {
        doubtful.emplace_back(r2, k);
      }
    }
    // The covariance test costs a solve per closure: the likeliest first, up to the budget.
    std::sort(doubtful.begin(), doubtful.end());
    doubtful.resize(std::min(doubtful.size(), static_cast<std::size_t>(gate.max_covariance_tests)));
    std::vector<PoseGraphEdge> candidates;
    for (const auto& [r2, k] : doubtful) candidates.push_back(graph.edges[k]);
    const std::vector<PredictedJoin> predicted = spa.predicted_joins(kept, candidates);
    gated.covariance_tests += candidates.size();
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const std::size_t k = doubtful[c].second;
      const bool lone = wide_support.partners[k] < gate.min_support;
      if (predicted[c].chi2 > gate2 || predicted[c].max_turn > (lone ? gate.max_lone_turn : gate.max_predicted_turn)) continue;
      admitted[k] = joined = true;
    }
    if (!joined) break;
  }

  // 3. The closures admitted one by one need not agree with each other: where the optimum leaves
  //    any beyond the gate, the membership kernel decides among them and the rest are optimised
  //    again.
  if (any_closure_beyond(kept, gate2) && membership.loop_kernel.type != config.loop_kernel.type) {
    const SparsePoseAdjustmentResult decided = optimize_pose_graph(kept, membership);
    for (std::size_t m = 0; m < index.size(); ++m) admitted[index[m]] = decided.edge_weights[m] >= 0.5;
    kept = edges_taken(graph, admitted, std::move(kept.poses), index);
    add_result(gated.optimization.result, decided);
    add_result(gated.optimization.result, spa.optimize(kept));
    gated.decided = true;
  }

  for (std::size_t k = 0; k < graph.edges.size(); ++k) gated.admitted += graph.edges[k].robust && admitted[k] ? 1 : 0;
  gated.refused = gated.loop_edges - gated.admitted;
  std::vector<double> weights(graph.edges.size(), 0.0);
  for (std::size_t m = 0; m < index.size(); ++m) weights[index[m]] = gated.optimization.result.edge_weights[m];
  gated.optimization.result.edge_weights = std::move(weights);
  graph.poses = std::move(kept.poses);
  return gated;
}

}  // namespace slam2d
