#include "slam2d/slam/graph/loop_closure.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

void validate(const LoopClosureConfig& config) {
  check(std::isfinite(config.search_radius) && config.search_radius > 0.0, "loop closure: search_radius must be > 0");
  check(std::isfinite(config.uncertainty_sigmas) && config.uncertainty_sigmas >= 0.0,
        "loop closure: uncertainty_sigmas must be >= 0");
  check(std::isfinite(config.max_search_radius) && config.max_search_radius >= config.search_radius,
        "loop closure: max_search_radius must be >= search_radius");
  check(std::isfinite(config.min_path_distance) && config.min_path_distance >= 0.0,
        "loop closure: min_path_distance must be >= 0");
  check(std::isfinite(config.map_radius) && config.map_radius > 0.0, "loop closure: map_radius must be > 0");
  check(std::isfinite(config.max_translation_variance) && config.max_translation_variance > 0.0,
        "loop closure: max_translation_variance must be > 0");
  check(config.min_chain_size >= 1, "loop closure: min_chain_size must be >= 1");
  check(config.max_chains >= 1, "loop closure: max_chains must be >= 1");
  check(config.max_near_chains >= 0, "loop closure: max_near_chains must be >= 0");
  check(config.search_interval >= 1, "loop closure: search_interval must be >= 1");
  check(config.min_inlier_fraction >= 0.0 && config.min_inlier_fraction <= 1.0,
        "loop closure: min_inlier_fraction must be in [0, 1]");
  validate(config.match);
}

std::vector<bool> nodes_within_graph_distance(const PoseGraph& graph, std::size_t source, double max_distance) {
  std::vector<std::vector<std::pair<std::size_t, double>>> adjacent(graph.size());
  for (const PoseGraphEdge& edge : graph.edges) {
    const double length = edge.T_from_to.translation().norm();
    adjacent[static_cast<std::size_t>(edge.from)].emplace_back(static_cast<std::size_t>(edge.to), length);
    adjacent[static_cast<std::size_t>(edge.to)].emplace_back(static_cast<std::size_t>(edge.from), length);
  }
  std::vector<double> distance(graph.size(), std::numeric_limits<double>::infinity());
  std::vector<bool> reached(graph.size(), false);
  using Entry = std::pair<double, std::size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  distance[source] = 0.0;
  queue.emplace(0.0, source);
  while (!queue.empty()) {
    const auto [d, node] = queue.top();
    queue.pop();
    if (reached[node]) continue;
    reached[node] = true;
    for (const auto& [next, length] : adjacent[node]) {
      const double candidate = d + length;
      if (candidate <= max_distance && candidate < distance[next]) {
        distance[next] = candidate;
        queue.emplace(candidate, next);
      }
    }
  }
  return reached;
}

std::vector<std::pair<std::size_t, std::size_t>> group_into_chains(const std::vector<std::size_t>& sorted_candidates,
                                                                   int min_size) {
  std::vector<std::pair<std::size_t, std::size_t>> chains;
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= sorted_candidates.size(); ++i) {
    const bool run_ends = i == sorted_candidates.size() || sorted_candidates[i] != sorted_candidates[i - 1] + 1;
    if (!run_ends) continue;
    if (i - begin >= static_cast<std::size_t>(min_size)) {
      chains.emplace_back(sorted_candidates[begin], sorted_candidates[i - 1] + 1);
    }
    begin = i;
  }
  return chains;
}

LoopCloser::LoopCloser(const LoopClosureConfig& config) : config_(config) { validate(config_); }

namespace {

const SE2& node_pose(const PoseGraph& graph, const Keyframe& keyframe) { return graph.poses[keyframe.node]; }

// Step 1: the keyframes near the estimate, outside the recent chain (ascending).
std::vector<std::size_t> loop_candidates(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                         std::size_t current, double radius, double min_path_distance) {
  const Eigen::Vector2d here = node_pose(graph, keyframes[current]).translation();
  const double path_here = keyframes[current].path_distance;
  std::vector<std::size_t> candidates;
  for (std::size_t k = 0; k < current; ++k) {
    if (path_here - keyframes[k].path_distance < min_path_distance) break;  // path distance grows with k
    if ((node_pose(graph, keyframes[k]).translation() - here).norm() <= radius) candidates.push_back(k);
  }
  return candidates;
}

double distance_to_chain(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                         std::pair<std::size_t, std::size_t> chain, const Eigen::Vector2d& point) {
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = chain.first; k < chain.second; ++k) {
    nearest = std::min(nearest, (node_pose(graph, keyframes[k]).translation() - point).norm());
  }
  return nearest;
}

std::size_t nearest_keyframe(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                             std::pair<std::size_t, std::size_t> chain, const Eigen::Vector2d& point) {
  std::size_t best = chain.first;
  for (std::size_t k = chain.first; k < chain.second; ++k) {
    if ((node_pose(graph, keyframes[k]).translation() - point).squaredNorm() <
        (node_pose(graph, keyframes[best]).translation() - point).squaredNorm()) {
      best = k;
    }
  }
  return best;
}

}  // namespace

std::optional<LoopClosure> LoopCloser::match_chain(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                                   std::size_t current, std::pair<std::size_t, std::size_t> chain,
                                                   const MapMatchConfig& match_config) const {
  std::vector<const Keyframe*> members;
  std::vector<SE2> poses;
  for (std::size_t k = chain.first; k < chain.second; ++k) {
    members.push_back(&keyframes[k]);
    poses.push_back(node_pose(graph, keyframes[k]));
  }
  const SE2& guess = node_pose(graph, keyframes[current]);
  const double map_radius = config_.map_radius + std::max(match_config.correlative.window_x, match_config.correlative.window_y);
  const MatchMap map = make_match_map(map_cloud(members, poses, guess.translation(), map_radius, match_config.map_voxel), match_config);
  const MapMatchResult match = match_scan_to_map(map, keyframes[current].cloud, guess, match_config);
  if (!match.converged || !match.refined || match.inlier_fraction < config_.min_inlier_fraction) return std::nullopt;
  if (config_.reject_degenerate && match.degenerate) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> translation(match.covariance.topLeftCorner<2, 2>());
  if (translation.eigenvalues().maxCoeff() > config_.max_translation_variance) return std::nullopt;
  const std::size_t anchor = nearest_keyframe(keyframes, graph, chain, match.T_map_robot.translation());
  const SE2& T_map_anchor = node_pose(graph, keyframes[anchor]);
  LoopClosure closure;
  closure.edge.from = static_cast<int>(keyframes[anchor].node);
  closure.edge.to = static_cast<int>(keyframes[current].node);
  closure.edge.T_from_to = T_map_anchor.between(match.T_map_robot);
  // The match's covariance is in the map frame; the edge's is in the anchor's frame.
  closure.edge.information = information_from_covariance(rotate_covariance(match.covariance, -T_map_anchor.theta()));
  closure.edge.robust = true;
  closure.score = match.score;
  closure.chain_begin = chain.first;
  closure.chain_end = chain.second;
  return closure;
}

std::vector<LoopClosure> LoopCloser::verify(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                            std::size_t current, double uncertainty_radius,
                                            std::size_t* attempts) const {
  const double radius = std::min(config_.max_search_radius, config_.search_radius + uncertainty_radius);
  const Eigen::Vector2d here = node_pose(graph, keyframes[current]).translation();
  auto chains = group_into_chains(loop_candidates(keyframes, graph, current, radius, config_.min_path_distance),
                                  config_.min_chain_size);
  if (chains.empty()) return {};
  std::sort(chains.begin(), chains.end(), [&](const auto& a, const auto& b) {
    return distance_to_chain(keyframes, graph, a, here) < distance_to_chain(keyframes, graph, b, here);
  });
  const std::vector<bool> linked =
      nodes_within_graph_distance(graph, keyframes[current].node, config_.min_path_distance);
  const bool search_large_window = current % static_cast<std::size_t>(config_.search_interval) == 0;
  int loops = search_large_window ? 0 : config_.max_chains;
  int near = 0;
  std::vector<LoopClosure> closures;
  for (const auto& chain : chains) {
    bool is_near = false;
    for (std::size_t k = chain.first; k < chain.second && !is_near; ++k) is_near = linked[keyframes[k].node];
    if (is_near ? near++ >= config_.max_near_chains : loops++ >= config_.max_chains) continue;
    if (attempts != nullptr && !is_near) ++*attempts;
    auto closure = match_chain(keyframes, graph, current, chain, is_near ? config_.near_match : config_.match);
    if (!closure) continue;
    closure->near = is_near;
    closures.push_back(*closure);
  }
  return closures;
}

std::vector<LoopClosure> LoopCloser::delay(std::vector<LoopClosure> verified) {
  std::vector<LoopClosure> ready;
  auto best = std::max_element(verified.begin(), verified.end(),
                               [](const LoopClosure& a, const LoopClosure& b) { return a.score < b.score; });
  const bool improves = best != verified.end() && pending_ && best->score > pending_->score &&
                        best->chain_begin < pending_->chain_end && pending_->chain_begin < best->chain_end;
  if (improves) {
    pending_ = *best;
    return ready;
  }
  if (pending_) ready.push_back(*pending_);
  pending_.reset();
  if (best != verified.end()) pending_ = *best;
  return ready;
}

std::vector<LoopClosure> LoopCloser::close(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                           std::size_t current, double uncertainty_radius, std::size_t* attempts) {
  if (!config_.enabled) return {};
  std::vector<LoopClosure> verified = verify(keyframes, graph, current, uncertainty_radius, attempts);
  if (!config_.delayed) return verified;
  return delay(std::move(verified));
}

std::optional<LoopClosure> LoopCloser::release() {
  std::optional<LoopClosure> released = pending_;
  pending_.reset();
  return released;
}

}  // namespace slam2d
