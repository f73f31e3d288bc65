// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/graph/loop_closure.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <queue>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {

Drift drift_along(const GraphPath& path, const DriftModel& model) {
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  if (!std::isfinite(path.distance) || !std::isfinite(path.turned)) return {.translation = kUnbounded, .rotation = kUnbounded};
  return {.translation = model.translation_per_metre * path.distance,
          .rotation = model.rotation_per_metre * path.distance + model.rotation_per_radian * path.turned};
}

void validate(const DriftModel& model) { check_fields(model, "DriftModel"); }

void validate(const LargeClosureConfig& config) {
  check_fields(config, "LargeClosureConfig");
  check(config.confirm_max_distance >= config.confirm_min_distance,
        "LargeClosureConfig: confirm_max_distance must be >= confirm_min_distance");
  validate(config.confirm_match);
  validate(config.global_coarse);
  validate(config.global_fine);
}

void validate(const LoopClosureConfig& config) {
  check_fields(config, "LoopClosureConfig");
  validate(config.match);
  validate(config.near_match);
  validate(config.large);
}

std::vector<std::optional<GraphPath>> gap_steps(const std::vector<Keyframe>& keyframes, std::size_t nodes,
                                                const DriftModel& model) {
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  std::vector<std::optional<GraphPath>> steps(nodes);
  for (const Keyframe& keyframe : keyframes) {
    if (!keyframe.after_gap || keyframe.node >= nodes) continue;
    // drift_along's inverse: the distance that gives the translation's drift, the turn that adds
    // what the distance does not give of the rotation's.
    const double distance = model.translation_per_metre > 0.0 && std::isfinite(keyframe.gap_drift_translation)
                                ? keyframe.gap_drift_translation / model.translation_per_metre
                                : kUnbounded;
    const double rest = keyframe.gap_drift_rotation - model.rotation_per_metre * distance;
    const double turned = !std::isfinite(distance) || !std::isfinite(rest) ? kUnbounded
                          : rest <= 0.0                                     ? 0.0
                          : model.rotation_per_radian > 0.0                 ? rest / model.rotation_per_radian
                                                                            : kUnbounded;
    steps[keyframe.node] = GraphPath{.distance = distance, .turned = turned};
  }
  return steps;
}

std::vector<GraphPath> graph_paths(const PoseGraph& graph, std::span<const std::size_t> sources, double max_distance,
                                   const std::vector<std::optional<GraphPath>>* steps) {
  struct Step {
    std::size_t to;
    double length, turn;
  };
  const auto gap_step = [&](const PoseGraphEdge& edge) -> const std::optional<GraphPath>* {
    const auto later = static_cast<std::size_t>(std::max(edge.from, edge.to));
    if (!steps || std::abs(edge.to - edge.from) != 1 || later >= steps->size() || !(*steps)[later]) return nullptr;
    return &(*steps)[later];
  };
  // The edges at each node, in the edges' order (compressed rows: two allocations, not one a node;
  // this runs for every keyframe that searches, over the whole graph).
  std::vector<std::size_t> first(graph.size() + 1, 0);
  for (const PoseGraphEdge& edge : graph.edges) {
    ++first[static_cast<std::size_t>(edge.from) + 1];
    ++first[static_cast<std::size_t>(edge.to) + 1];
  }
  for (std::size_t n = 0; n < graph.size(); ++n) first[n + 1] += first[n];
  std::vector<Step> adjacent(first.back());
  std::vector<std::size_t> filled(first.begin(), first.end() - 1);
  for (const PoseGraphEdge& edge : graph.edges) {
    const std::optional<GraphPath>* gap = gap_step(edge);
    const double length = gap ? (*gap)->distance : edge.T_from_to.translation().norm();
    const double turn = gap ? (*gap)->turned : std::abs(edge.T_from_to.theta());
    adjacent[filled[static_cast<std::size_t>(edge.from)]++] = {static_cast<std::size_t>(edge.to), length, turn};
    adjacent[filled[static_cast<std::size_t>(edge.to)]++] = {static_cast<std::size_t>(edge.from), length, turn};
  }
  constexpr double kUnreached = std::numeric_limits<double>::infinity();
  std::vector<GraphPath> paths(graph.size(), GraphPath{.distance = kUnreached, .turned = kUnreached});
  std::vector<bool> done(graph.size(), false);
  using Entry = std::pair<double, std::size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (const std::size_t source : sources) {
    paths[source] = {};
    queue.emplace(0.0, source);
  }
  while (!queue.empty()) {
    const std::size_t node = queue.top().second;
    queue.pop();
    if (done[node]) continue;
    done[node] = true;
    for (std::size_t k = first[node]; k < first[node + 1]; ++k) {
      const Step& step = adjacent[k];
      const double distance = paths[node].distance + step.length;
      if (distance <= max_distance && distance < paths[step.to].distance) {
        paths[step.to] = {.distance = distance, .turned = paths[node].turned + step.turn};
        queue.emplace(distance, step.to);
      }
    }
  }
  return paths;
}

std::vector<bool> nodes_within_graph_distance(const PoseGraph& graph, std::span<const std::size_t> sources,
                                              double max_distance, const std::vector<std::optional<GraphPath>>* steps) {
  const std::vector<GraphPath> paths = graph_paths(graph, sources, max_distance, steps);
  std::vector<bool> reached(paths.size());
  for (std::size_t n = 0; n < paths.size(); ++n) reached[n] = paths[n].distance <= max_distance;
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

// Per earlier keyframe, from the current one: the search radius and heading window the drift
// allows (uncertainty_sigmas sigmas), and whether the graph already links it (near).
struct LoopCloser::Uncertainty {
  std::vector<double> radius;   // m
  std::vector<double> heading;  // rad
  std::vector<bool> linked;
};

namespace {

using Chain = std::pair<std::size_t, std::size_t>;

const SE2& node_pose(const PoseGraph& graph, const Keyframe& keyframe) { return graph.poses[keyframe.node]; }

// Step 1: the keyframes k within radius(k) of `center`, outside the recent chain of `current` (ascending).
std::vector<std::size_t> loop_candidates(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                         std::size_t current, const Eigen::Vector2d& center,
                                         const std::function<double(std::size_t)>& radius, double min_path_distance) {
  const double path_here = keyframes[current].path_distance;
  std::vector<std::size_t> candidates;
  for (std::size_t k = 0; k < current; ++k) {
    if (path_here - keyframes[k].path_distance < min_path_distance) break;  // path distance grows with k
    if (keyframes[k].released) continue;  // no points left to match against
    if ((node_pose(graph, keyframes[k]).translation() - center).norm() <= radius(k)) candidates.push_back(k);
  }
  return candidates;
}

// The constant radius of the local search and of confirmations.
std::function<double(std::size_t)> constant(double radius) {
  return [radius](std::size_t) { return radius; };
}

double distance_to_chain(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, Chain chain,
                         const Eigen::Vector2d& point) {
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = chain.first; k < chain.second; ++k) {
    nearest = std::min(nearest, (node_pose(graph, keyframes[k]).translation() - point).norm());
  }
  return nearest;
}

std::size_t nearest_keyframe(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, Chain chain,
                             const Eigen::Vector2d& point) {
  std::size_t best = chain.first;
  for (std::size_t k = chain.first; k < chain.second; ++k) {
    if ((node_pose(graph, keyframes[k]).translation() - point).squaredNorm() <
        (node_pose(graph, keyframes[best]).translation() - point).squaredNorm()) {
      best = k;
    }
  }
  return best;
}

bool is_linked(const std::vector<Keyframe>& keyframes, const std::vector<bool>& linked, Chain chain) {
  for (std::size_t k = chain.first; k < chain.second; ++k) {
    if (linked[keyframes[k].node]) return true;
  }
  return false;
}

// Steps 1-2 around `center`: the chains of keyframes k within radius(k), nearest first, without
// those the graph already links to `current` unless asked (they are near chains, no loop).
std::vector<Chain> chains_around(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, std::size_t current,
                                 const Eigen::Vector2d& center, const std::function<double(std::size_t)>& radius,
                                 const LoopClosureConfig& config, const std::vector<bool>& linked, bool keep_linked) {
  std::vector<Chain> chains = group_into_chains(
      loop_candidates(keyframes, graph, current, center, radius, config.min_path_distance), config.min_chain_size);
  if (!keep_linked) std::erase_if(chains, [&](const Chain& chain) { return is_linked(keyframes, linked, chain); });
  std::sort(chains.begin(), chains.end(), [&](const Chain& a, const Chain& b) {
    return distance_to_chain(keyframes, graph, a, center) < distance_to_chain(keyframes, graph, b, center);
  });
  return chains;
}

// Karto's response at the matched pose: the mean over the scan's points of a Gaussian (the search
// kernel's sigma) of their distance to the map, point to line where the map point has a normal.
// Unlike the score (the share of points on the table's cells, which saturates at 1 for any good
// match), it keeps rising as a match gets better, so that two closures of a chain can be told apart.
double response(const MatchMap& map, const PointCloud2& scan, const SE2& T_map_robot, double sigma) {
  const PointCloud2& target = map.grid.target();
  double sum = 0.0;
  for (const Point2& point : scan.points) {
    const Point2 p = T_map_robot * point;
    const Neighbor nearest = map.grid.tree().nearest(p);
    if (nearest.index >= target.size()) continue;
    double squared = nearest.squared_distance;
    if (target.has_normals() && target.normals[nearest.index].squaredNorm() > 0.0) {
      const double along_normal = target.normals[nearest.index].dot(p - target.points[nearest.index]);
      squared = along_normal * along_normal;
    }
    sum += std::exp(-0.5 * squared / (sigma * sigma));
  }
  return scan.empty() ? 0.0 : sum / static_cast<double>(scan.size());
}

double largest_window(const CorrelativeConfig& correlative) {
  return std::max(correlative.window_x, correlative.window_y);
}

}  // namespace

// Step 3: the keyframe's scan matched against the chain's map from `guess` (coarse to fine when a
// coarse configuration is given), and the edge from the chain's keyframe nearest to the match.
std::optional<LoopClosure> LoopCloser::match_chain(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                                   std::size_t current, Chain chain, const SE2& guess,
                                                   const MapMatchConfig& match_config,
                                                   const MapMatchConfig* coarse) const {
  std::vector<const Keyframe*> members;
  std::vector<SE2> poses;
  for (std::size_t k = chain.first; k < chain.second; ++k) {
    members.push_back(&keyframes[k]);
    poses.push_back(node_pose(graph, keyframes[k]));
  }
  const PointCloud2& scan = keyframes[current].cloud;
  SE2 start = guess;
  if (coarse != nullptr) {
    const double radius = config_.map_radius + largest_window(coarse->correlative);
    const MatchMap map =
        make_match_map(map_cloud(members, poses, guess.translation(), radius, coarse->map_voxel), *coarse);
    const MatchResult found = match_correlative_map(map, scan, guess, *coarse);
    if (!found.converged) return std::nullopt;
    start = found.T_target_source;
  }
  const double radius = config_.map_radius + largest_window(match_config.correlative);
  const MatchMap map =
      make_match_map(map_cloud(members, poses, start.translation(), radius, match_config.map_voxel), match_config);
  const MatchResult match = match_correlative_map(map, scan, start, match_config);
  if (!match.converged || match.inlier_fraction < config_.min_inlier_fraction) return std::nullopt;
  if (config_.reject_degenerate && match.degenerate) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> translation(match.covariance.topLeftCorner<2, 2>());
  if (translation.eigenvalues().maxCoeff() > config_.max_translation_variance) return std::nullopt;
  const std::size_t anchor = nearest_keyframe(keyframes, graph, chain, match.T_target_source.translation());
  const SE2& T_map_anchor = node_pose(graph, keyframes[anchor]);
  const SE2& estimate = node_pose(graph, keyframes[current]);
  LoopClosure closure;
  closure.edge.from = static_cast<int>(keyframes[anchor].node);
  closure.edge.to = static_cast<int>(keyframes[current].node);
  closure.edge.T_from_to = T_map_anchor.between(match.T_target_source);
  // The match's covariance is in the map frame; the edge's is in the anchor's frame.
  closure.edge.information = information_from_covariance(rotate_covariance(match.covariance, -T_map_anchor.theta()));
  closure.edge.robust = true;
  closure.edge.closure = true;
  closure.score = match.score;
  closure.response = response(map, scan, match.T_target_source, match_config.correlative.sigma);
  closure.inlier_fraction = match.inlier_fraction;
  closure.keyframe = current;
  closure.anchor = anchor;
  closure.chain_begin = chain.first;
  closure.chain_end = chain.second;
  closure.T_map_matched = match.T_target_source;
  closure.correction_translation = (match.T_target_source.translation() - estimate.translation()).norm();
  closure.correction_rotation = std::abs(angle_difference(match.T_target_source.theta(), estimate.theta()));
  // A scan that fits the chain's walls from behind them, far from where the graph puts it, is an L
  // of walls fitted onto a corner from beyond it (the hospital world's 3.4 m false closure). Near
  // the estimate it is a thin wall's other face where the map holds only one (Intel without
  // odometry: refusing those costs 0.0200 -> 0.0356 m).
  if (match.seen_from_behind && is_large(closure)) return std::nullopt;
  return closure;
}

LoopCloser::Uncertainty LoopCloser::uncertainty(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                                std::size_t current) const {
  const std::vector<std::optional<GraphPath>> gaps = gap_steps(keyframes, graph.size(), config_.drift);
  const std::vector<GraphPath> paths = graph_paths(graph, keyframes[current].node,
                                                   std::numeric_limits<double>::infinity(), &gaps);
  Uncertainty uncertainty;
  uncertainty.radius.resize(paths.size());
  uncertainty.heading.resize(paths.size());
  uncertainty.linked.resize(paths.size());
  for (std::size_t n = 0; n < paths.size(); ++n) {
    const Drift drift = drift_along(paths[n], config_.drift);
    uncertainty.radius[n] = config_.uncertainty_sigmas * drift.translation;
    uncertainty.heading[n] = config_.uncertainty_sigmas * drift.rotation;
    uncertainty.linked[n] = paths[n].distance <= config_.min_path_distance;
  }
  return uncertainty;
}

LoopCloser::Verified LoopCloser::verify(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                        std::size_t current, const Uncertainty& uncertainty, bool search_large_window) {
  const SE2& estimate = node_pose(graph, keyframes[current]);
  const std::vector<Chain> chains = chains_around(keyframes, graph, current, estimate.translation(),
                                                  constant(config_.search_radius), config_, uncertainty.linked, true);
  int loops = search_large_window ? 0 : config_.max_chains;
  int near = 0;
  Verified verified;
  for (const Chain& chain : chains) {
    const bool is_near = is_linked(keyframes, uncertainty.linked, chain);
    if (is_near ? near++ >= config_.max_near_chains : loops++ >= config_.max_chains) continue;
    if (!is_near) {
      ++stats_.attempts;
      verified.attempted.push_back(chain);
    }
    auto closure =
        match_chain(keyframes, graph, current, chain, estimate, is_near ? config_.near_match : config_.match);
    if (!closure) continue;
    closure->search = is_near ? LoopSearch::kNear : LoopSearch::kLocal;
    verified.closures.push_back(*closure);
  }
  return verified;
}

// The global search: the chains within the drift radius whose drift the large window does not
// cover, nearest first, up to max_global_chains, each searched over a window that covers its
// drift, coarse to fine; the best closure that passes the strict thresholds and lies within the
// drift.
std::optional<LoopClosure> LoopCloser::search_globally(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                                       std::size_t current, const Uncertainty& uncertainty) {
  const LargeClosureConfig& large = config_.large;
  const CorrelativeConfig& local = config_.match.correlative;
  const auto radius = [&](std::size_t k) {
    return std::min(large.max_global_radius, config_.search_radius + uncertainty.radius[keyframes[k].node]);
  };
  const SE2& estimate = node_pose(graph, keyframes[current]);
  std::vector<Chain> chains =
      chains_around(keyframes, graph, current, estimate.translation(), radius, config_, uncertainty.linked, false);
  struct Reach {
    double drift = 0.0;    // m, the largest drift radius of the chain's keyframes
    double heading = 0.0;  // rad
  };
  const auto reach = [&](const Chain& chain) {
    Reach r;
    for (std::size_t k = chain.first; k < chain.second; ++k) {
      r.drift = std::max(r.drift, uncertainty.radius[keyframes[k].node]);
      r.heading = std::max(r.heading, uncertainty.heading[keyframes[k].node]);
    }
    return r;
  };
  std::erase_if(chains, [&](const Chain& chain) {  // the large window covers their drift
    const Reach r = reach(chain);
    return r.drift <= largest_window(local) && r.heading <= local.window_theta;
  });
  std::erase_if(chains, [&](const Chain& chain) { return is_held(chain); });  // closed, once the robot leaves it
  if (chains.empty()) return std::nullopt;
  const auto started = std::chrono::steady_clock::now();
  ++stats_.global_searches;
  last_global_ = current;
  std::optional<LoopClosure> best;
  for (std::size_t c = 0; c < chains.size() && c < static_cast<std::size_t>(large.max_global_chains); ++c) {
    const Reach r = reach(chains[c]);
    MapMatchConfig coarse = large.global_coarse;
    coarse.correlative.window_x = coarse.correlative.window_y =
        std::clamp(r.drift, largest_window(local), large.max_global_window);
    coarse.correlative.window_theta = std::clamp(r.heading, local.window_theta, std::numbers::pi);
    ++stats_.global_chains;
    auto closure = match_chain(keyframes, graph, current, chains[c], estimate, large.global_fine, &coarse);
    if (!closure || !passes_strict(*closure) || !within_drift(*closure, uncertainty)) continue;
    if (!best || closure->score > best->score) best = closure;
  }
  if (best) best->search = LoopSearch::kGlobal;
  stats_.global_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return best;
}

// The second keyframe of a large correction: matched over a small window at the pose the first
// closure's correction predicts for it, against the chains around that pose.
std::optional<LoopClosure> LoopCloser::confirm(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                               std::size_t current) const {
  const LoopClosure& first = *pending_large_;
  const LargeClosureConfig& large = config_.large;
  const double apart = std::abs(keyframes[current].path_distance - keyframes[first.keyframe].path_distance);
  if (current == first.keyframe || apart < large.confirm_min_distance || apart > large.confirm_max_distance) {
    return std::nullopt;
  }
  // The correction the first closure claims, T_matched * T_estimate^-1 in the map frame, with the
  // graph as it is now (the edge is relative to its anchor).
  const SE2 T_map_matched = node_pose(graph, keyframes[first.anchor]) * first.edge.T_from_to;
  const SE2 correction = T_map_matched * node_pose(graph, keyframes[first.keyframe]).inverse();
  const SE2 guess = correction * node_pose(graph, keyframes[current]);
  const std::vector<std::optional<GraphPath>> gaps = gap_steps(keyframes, graph.size(), config_.drift);
  const std::vector<bool> linked =
      nodes_within_graph_distance(graph, keyframes[current].node, config_.min_path_distance, &gaps);
  const std::vector<Chain> chains = chains_around(keyframes, graph, current, guess.translation(),
                                                  constant(config_.search_radius), config_, linked, false);
  for (std::size_t c = 0; c < chains.size() && c < static_cast<std::size_t>(config_.max_chains); ++c) {
    auto closure = match_chain(keyframes, graph, current, chains[c], guess, large.confirm_match);
    if (!closure || !passes_strict(*closure)) continue;
    const SE2 disagreement = guess.between(closure->T_map_matched);
    if (disagreement.translation().norm() > large.confirm_tolerance ||
        std::abs(disagreement.theta()) > large.confirm_rotation_tolerance) {
      continue;
    }
    closure->search = LoopSearch::kConfirmation;
    return closure;
  }
  return std::nullopt;
}

// A large correction confirmed by a keyframe before it (the nearest first): at once when it is
// found, and at the end of a log, when no keyframe after it could.
std::optional<LoopClosure> LoopCloser::confirm_before(const std::vector<Keyframe>& keyframes,
                                                      const PoseGraph& graph) const {
  const std::size_t first = pending_large_->keyframe;
  for (std::size_t k = first; k-- > 0;) {
    if (keyframes[first].path_distance - keyframes[k].path_distance > config_.large.confirm_max_distance) break;
    if (auto second = confirm(keyframes, graph, k)) return second;
  }
  return std::nullopt;
}

bool LoopCloser::is_large(const LoopClosure& closure) const {
  return closure.correction_translation > config_.large.min_translation ||
         closure.correction_rotation > config_.large.min_rotation;
}

bool LoopCloser::passes_strict(const LoopClosure& closure) const {
  return closure.score >= config_.large.min_score && closure.inlier_fraction >= config_.large.min_inlier_fraction;
}

// A large correction must lie within the drift the model allows between the keyframe and the
// chain's keyframe it links to.
bool LoopCloser::within_drift(const LoopClosure& closure, const Uncertainty& uncertainty) const {
  const auto anchor = static_cast<std::size_t>(closure.edge.from);  // its node
  return closure.correction_translation <= std::max(config_.large.min_translation, uncertainty.radius[anchor]) &&
         closure.correction_rotation <= std::max(config_.large.min_rotation, uncertainty.heading[anchor]);
}

// A large correction and its confirmation go in together, without the robust kernel (which would
// hardly let them pull); a global closure that turned out small keeps the kernel.
std::vector<LoopClosure> LoopCloser::confirmed(LoopClosure second) {
  LoopClosure first = *pending_large_;
  pending_large_.reset();
  const bool large = is_large(first) || is_large(second);
  first.edge.robust = second.edge.robust = !large;
  if (large) ++stats_.large_closures;
  if (first.search == LoopSearch::kGlobal) ++stats_.global_closures;
  return {first, second};
}

namespace {

// Two chains are the same place when their runs of keyframes overlap (a chain found again from a
// keyframe further on has moved along with the robot).
bool same_chain(const LoopClosure& closure, std::size_t begin, std::size_t end) {
  return closure.chain_begin < end && begin < closure.chain_end;
}

}  // namespace

// A chain with a closure held back (delayed mode): it is closed, only later; a large correction
// to it, or a global search over it, would be a second, conflicting closure of the same chain.
bool LoopCloser::is_held(Chain chain) const {
  return std::any_of(held_.begin(), held_.end(),
                     [&](const LoopClosure& held) { return same_chain(held, chain.first, chain.second); });
}

// Delayed loop closure, from a keyframe that searched the large window: the held closures whose
// chain this search did not attempt are closed (the robot has left them); each new closure
// replaces the held one of its chain when its response is higher and is dropped when not, or is
// held as the first of its chain.
std::vector<LoopClosure> LoopCloser::delay(const std::vector<LoopClosure>& verified,
                                           const std::vector<Chain>& attempted) {
  std::vector<LoopClosure> ready;
  std::erase_if(held_, [&](const LoopClosure& held) {
    const bool left = std::none_of(attempted.begin(), attempted.end(),
                                   [&](const Chain& chain) { return same_chain(held, chain.first, chain.second); });
    if (left) ready.push_back(held);
    return left;
  });
  for (const LoopClosure& closure : verified) {
    auto same = std::find_if(held_.begin(), held_.end(), [&](const LoopClosure& held) {
      return same_chain(held, closure.chain_begin, closure.chain_end);
    });
    if (same == held_.end()) {
      held_.push_back(closure);
    } else if (closure.response > same->response) {
      *same = closure;
      ++stats_.held_replaced;
    } else {
      ++stats_.held_dropped;
    }
  }
  return ready;
}

std::vector<LoopClosure> LoopCloser::close(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                           std::size_t current, bool final) {
  if (!config_.enabled) return {};
  const LargeClosureConfig& large = config_.large;
  // A large correction waiting for its confirmation: confirmed from here, or dropped when too far.
  if (pending_large_) {
    if (auto second = confirm(keyframes, graph, current)) return confirmed(*second);
    const double apart = keyframes[current].path_distance - keyframes[pending_large_->keyframe].path_distance;
    if (apart > large.confirm_max_distance) {
      pending_large_.reset();
      ++stats_.unconfirmed;
    }
  }
  const bool search_large_window = final || current % static_cast<std::size_t>(config_.search_interval) == 0;
  if (!search_large_window && config_.max_near_chains == 0) return {};
  if (search_large_window) last_searched_ = current;
  const Uncertainty drift = uncertainty(keyframes, graph, current);
  std::vector<LoopClosure> closures;
  std::vector<LoopClosure> loops;
  std::optional<LoopClosure> large_found;
  const Verified verified = verify(keyframes, graph, current, drift, search_large_window);
  for (const LoopClosure& closure : verified.closures) {
    if (closure.near()) {
      closures.push_back(closure);
    } else if (!is_large(closure)) {
      loops.push_back(closure);
    } else if (passes_strict(closure) && within_drift(closure, drift) &&
               !is_held({closure.chain_begin, closure.chain_end}) &&
               (!large_found || closure.score > large_found->score)) {
      large_found = closure;
    }
  }
  // Nothing found where the estimate is: chains whose drift the large window does not cover.
  const bool global_due =
      final || !last_global_ || current >= *last_global_ + static_cast<std::size_t>(large.global_interval);
  if (search_large_window && large.global_search && loops.empty() && !large_found && !pending_large_ && global_due) {
    large_found = search_globally(keyframes, graph, current, drift);
  }
  if (config_.delayed && search_large_window) loops = delay(loops, verified.attempted);
  closures.insert(closures.end(), loops.begin(), loops.end());
  if (large_found && !pending_large_) {
    pending_large_ = large_found;
    if (auto second = confirm_before(keyframes, graph)) {
      for (const LoopClosure& closure : confirmed(*second)) closures.push_back(closure);
    }
  }
  return closures;
}

std::vector<LoopClosure> LoopCloser::release() {
  std::vector<LoopClosure> released = std::move(held_);
  held_.clear();
  if (pending_large_) {  // the log ended before a keyframe further on could confirm it
    pending_large_.reset();
    ++stats_.unconfirmed;
  }
  return released;
}

}  // namespace slam2d
