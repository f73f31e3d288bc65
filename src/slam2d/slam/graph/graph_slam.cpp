// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/graph/graph_slam.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <numbers>
#include <span>
#include <string>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/registration/free_space_check.hpp"
#include "slam2d/registration/match_fusion.hpp"
#include "slam2d/registration/normals.hpp"
#include "slam2d/core/scan_preprocessing.hpp"

namespace slam2d {

namespace {

// A loop edge is one the loop closer made (sequential and odometry edges join consecutive nodes
// until merged nodes move them: keyframes.merge_released).
bool loop_edge(const PoseGraphEdge& edge) { return edge.closure; }

// Whether a global search found one of these closures (a large correction and its confirmation).
bool found_globally(const std::vector<LoopClosure>& closures) {
  return std::any_of(closures.begin(), closures.end(),
                     [](const LoopClosure& closure) { return closure.search == LoopSearch::kGlobal; });
}

// What a sequential edge keeps of its information when the odometry beside it outvoted it.
constexpr double kOutvotedWeight = 1e-6;

}  // namespace

HectorSlamConfig default_tracking_config() {
  HectorSlamConfig config;
  config.prior_from_motion_noise = true;         // the prior weighed by the odometry's learnt noise,
  config.prior_kernel = kOdometryPriorKernel;    // under Hector's Cauchy kernel: the scan wins far off,
  config.recovery_residual = 0.25;               // a poor fit is retried within a quarter turn;
  config.prior_information_translation = 100.0;  // until a match has told the noise (and where the
  config.prior_information_rotation = 300.0;     // odometry is Hector's: map_job), sigma 0.1 m, 0.058 rad
  config.prior_sigma_per_metre = 0.0;            // for every increment,
  config.prior_at_catch_ups = true;              // catch-ups included (degraded acapulco: 0.43 m, 1.00 without)
  config.matcher.degeneracy_ratio = 0.01;        // along a corridor's axis the prediction stands
                                                 // (and where only the map's far dots would pin it: Hector's)
  config.odometry_guard.confirm_burst = 0.0;     // the kernel already yields to the scans (below)
  config.odometry_calibration.window = 1000.0;   // and the odometry's systematic error, by what of it
  config.odometry_calibration.significance = 5.0;  // stands out of five standard errors
  return config;
}

void validate(const GraphSlamConfig& config) {
  check_fields(config, "GraphSlamConfig");
  check(config.max_range > config.min_range, "GraphSlamConfig: max_range must be > min_range");
  validate(config.tracking);
  validate(config.loop_closure);
  validate(config.odometry_noise);
}

GraphSlam::GraphSlam(const GraphSlamConfig& config)
    : config_(config),
      selector_(config.keyframes),
      back_end_(config.back_end),
      loop_closer_(config.loop_closure),
      odometry_noise_(config.odometry_noise),
      gaps_(config.gap) {
  validate(config_);
}

SE2 GraphSlam::current_pose() const {
  if (scans_.empty()) return SE2();
  const ScanRecord& last = scans_.back();
  return graph_.poses[keyframes_[last.keyframe].node] * last.T_keyframe_robot;
}

PointCloud2 GraphSlam::scan_cloud(const LaserScan& scan) const {
  PointCloud2 cloud;
  cloud.points = usable_end_points(scan, config_.min_range, config_.max_range);
  estimate_normals_ordered(cloud);
  return cloud;
}

// The scan matched against the tracker's map (its own frame), from the odometry prediction when
// the scans come with odometry (with the weak prior and solution remapping), else from the last
// pose (Hector's own matching).
HectorStep GraphSlam::track(const LaserScan& scan, const std::optional<SE2>& T_odom_robot) {
  if (!tracker_) {
    HectorSlamConfig config = config_.tracking;
    config.prior = T_odom_robot ? MotionPrior::kOdometry : MotionPrior::kLastPose;
    config.relocalization.enabled = false;  // graph SLAM restarts its map at a gap; the loop closer searches
    if (!T_odom_robot) {  // the last pose is no measurement of where the robot is: neither a prior
      config.prior_information_translation = 0.0;  // at it nor a reason to stay there
      config.prior_information_rotation = 0.0;
      config.matcher.degeneracy_ratio = 0.0;
    }
    tracker_.emplace(config);
  }
  const bool with_odometry = tracker_->config().prior == MotionPrior::kOdometry;
  check(with_odometry == T_odom_robot.has_value(),
        "graph slam: odometry must come with every scan or with none (it changed at scan " +
            std::to_string(stats_.scans) + ")");
  HectorInputs inputs;
  inputs.T_odom_robot = T_odom_robot;
  return tracker_->add_scan(scan, inputs);
}

GraphSlamStep GraphSlam::add_scan(const LaserScan& scan, const std::optional<SE2>& T_odom_robot) {
  GraphSlamStep step;
  const double gap = gaps_.gap_before(scan.stamp);
  if (gap > 0.0 && tracker_) {
    ++stats_.gaps;
    const Drift drift = odometry_drift_over(gap);
    const double sigmas = config_.loop_closure.uncertainty_sigmas;
    if (within_tracker_reach(config_.gap, sigmas * drift.translation, sigmas * drift.rotation)) {
      ++stats_.gaps_tracked_through;  // the odometry is good enough: the tracker's map stays
    } else {
      tracker_->restart_map();
    }
  }
  const HectorStep tracked = track(scan, T_odom_robot);
  const bool first = keyframes_.empty();
  // The tracked motion since the last keyframe, carried from its (optimised) graph pose.
  const SE2 estimate = first ? SE2() : graph_.poses[keyframes_.back().node] * T_tracker_keyframe_.between(tracked.T_map_robot);
  step.matched = tracked.matched && !tracked.match.degenerate;
  accumulate_odometry(tracked);
  if (first || gap > 0.0 || selector_.is_keyframe(estimate, scan.stamp)) {
    add_keyframe(scan, estimate, tracked, T_odom_robot, first || gap > 0.0 || step.matched, gap);
    T_tracker_keyframe_ = tracked.T_map_robot;
    step.keyframe = true;
    step.loop_closures = close_loops(keyframes_.size() - 1, false);
    if (lifelong()) release_redundant();
  } else {
    const std::size_t keyframe = keyframes_.size() - 1;
    scans_.push_back({scan.stamp, keyframe, graph_.poses[keyframes_[keyframe].node].between(estimate)});
  }
  ++stats_.scans;
  step.T_map_robot = current_pose();
  return step;
}

// The odometry's increment since the last keyframe, intact while the guard trusted every one.
void GraphSlam::accumulate_odometry(const HectorStep& tracked) {
  if (tracked.odometry.first || tracked.odometry.trusted()) {
    odometry_since_keyframe_ = odometry_since_keyframe_ * tracked.odometry.increment;
  } else {
    odometry_intact_ = false;
  }
}

// The tracker's match covariance at the keyframe, twice (the previous keyframe was matched against
// the same local map), on the floor of the sequential sigmas and inflated along a degenerate
// direction (registration/match_fusion.hpp). A scan that told nothing (no usable points: a blind
// stretch) leaves the step to the odometry, with the odometry's own noise since the last keyframe,
// so that a loop's correction goes where nothing but the odometry held the path.
Covariance3 GraphSlam::sequential_covariance(const HectorStep& tracked) const {
  const double floor = config_.sequential_sigma_translation;
  const Covariance3 fixed = covariance_from_sigmas(floor, floor, config_.sequential_sigma_rotation);
  if (!config_.sequential_from_match || !tracked.matched || !odometry_intact_) return fixed;
  MatchResult match = tracked.match;
  match.covariance *= 2.0;
  const MatchNoiseConfig noise{.floor_translation = floor,
                               .floor_rotation = config_.sequential_sigma_rotation,
                               .degenerate_sigma = config_.degenerate_sigma};
  const MotionMeasurement measurement = match_measurement(match, noise);
  if (measurement.covariance.diagonal().maxCoeff() < kUnknownVariance) return measurement.covariance;
  return fixed + odometry_noise().covariance(odometry_since_keyframe_);
}

// The odometry edge beside a sequential edge: the guarded odometry's increment between the two
// keyframes with the motion noise model's covariance; the two edges' agreement teaches the model.
// Where they disagree beyond the gate, the one surer along the difference stands alone: the
// odometry edge is left out, or the sequential edge keeps next to no information.
void GraphSlam::add_odometry_edge(PoseGraphEdge& sequential) {
  const Covariance3 covariance = odometry_noise_.covariance(odometry_since_keyframe_);
  const Covariance3 sequential_covariance = sequential.information.inverse();
  const FusionOutcome outcome =
      fuse_motion({odometry_since_keyframe_, covariance}, {sequential.T_from_to, sequential_covariance}).outcome;
  stats_.fusion.count(outcome);
  if (outcome == FusionOutcome::kMatchWon) return;
  if (outcome == FusionOutcome::kOdometryWon) sequential.information *= kOutvotedWeight;
  PoseGraphEdge edge = sequential;
  edge.T_from_to = odometry_since_keyframe_;
  edge.information = information_from_covariance(covariance);
  graph_.edges.push_back(edge);
  ++stats_.odometry_edges;
  odometry_noise_.observe(odometry_since_keyframe_, sequential.T_from_to, sequential_covariance);
}

// How far the odometry drifted from the graph's estimate (the tracker's motion, loops closed) over
// stretches of `duration` seconds between the keyframes since the last gap (core/scan_gaps.hpp).
Drift GraphSlam::odometry_drift_over(double duration) const {
  std::size_t begin = keyframes_.size();
  while (begin > 0 && !keyframes_[begin - 1].after_gap) --begin;
  if (begin > 0) --begin;  // the keyframe after the last gap opens the stretch
  std::vector<OdometryAndEstimate> history;
  for (std::size_t k = begin; k < keyframes_.size() && keyframe_odometry_[k]; ++k) {
    history.push_back({keyframes_[k].stamp, *keyframe_odometry_[k], graph_.poses[keyframes_[k].node]});
  }
  return slam2d::odometry_drift_over(history, duration);
}

// The edge across a gap of `gap` seconds: the odometry's drift over it as standard deviations, on
// the sequential edges' floor (the motion noise model, linear in one increment's length, would
// count the tens of metres of a gap's increment as one step: 2 rad on ACES, where the odometry
// drifts 0.3 rad in that time). Unbounded: the motion noise of a path of gap.speed x gap (at least
// the increment's own length) with the increment's turn. The heading's sigma at most pi.
Covariance3 GraphSlam::gap_covariance(const SE2& increment, double gap, const Drift& drift) const {
  Covariance3 covariance;
  if (std::isfinite(drift.translation) && std::isfinite(drift.rotation)) {
    const double translation = std::max(drift.translation, config_.sequential_sigma_translation);
    covariance = covariance_from_sigmas(translation, translation, std::max(drift.rotation, config_.sequential_sigma_rotation));
  } else {
    const double path = std::max(increment.translation().norm(), config_.gap.speed * gap);
    covariance = odometry_noise().covariance(SE2(path, 0.0, increment.theta()));
  }
  covariance(2, 2) = std::min(covariance(2, 2), std::numbers::pi * std::numbers::pi);
  return covariance;
}

void GraphSlam::add_keyframe(const LaserScan& scan, const SE2& estimate, const HectorStep& tracked,
                             const std::optional<SE2>& T_odom_robot, bool matched, double gap) {
  Keyframe keyframe;
  keyframe.node = graph_.poses.size();
  keyframe.scan = stats_.scans;
  keyframe.stamp = scan.stamp;
  keyframe.cloud = scan_cloud(scan);
  if (keyframes_.empty()) {
    keyframe_motion_.push_back(SE2());
  } else {
    const Keyframe& previous = keyframes_.back();
    const SE2& T_map_previous = graph_.poses[previous.node];
    const double moved = (estimate.translation() - T_map_previous.translation()).norm();
    keyframe.path_distance = previous.path_distance + std::max(moved, config_.gap.speed * gap);
    PoseGraphEdge edge;
    edge.from = static_cast<int>(previous.node);
    edge.to = static_cast<int>(keyframe.node);
    edge.T_from_to = T_map_previous.between(estimate);
    if (gap > 0.0) {
      const Drift drift = odometry_drift_over(gap);
      keyframe.after_gap = true;
      keyframe.gap_drift_translation = drift.translation;
      keyframe.gap_drift_rotation = drift.rotation;
      edge.information = information_from_covariance(gap_covariance(edge.T_from_to, gap, drift));
    } else {
      edge.information = information_from_covariance(sequential_covariance(tracked));
    }
    if (config_.odometry_edges && odometry_intact_ && gap == 0.0) add_odometry_edge(edge);
    graph_.edges.push_back(edge);
    keyframe_motion_.push_back(edge.T_from_to);
    if (!matched) ++stats_.sequential_failures;
  }
  odometry_since_keyframe_ = SE2();
  odometry_intact_ = tracker_ && tracker_->config().prior == MotionPrior::kOdometry;
  graph_.poses.push_back(estimate);
  selector_.accept(estimate, scan.stamp);
  scans_.push_back({scan.stamp, keyframes_.size(), SE2()});
  keyframe_odometry_.push_back(T_odom_robot);
  keyframes_.push_back(std::move(keyframe));
  keyframe_scans_.push_back(scan);
  ++stats_.keyframes;
}

// Adds the closures' edges; the graph is optimised when one of them closes a loop (a near link
// only keeps the chain in place). A confirmed large correction, with check_large_closures, goes in
// only when the closures that agree with it are at least as many as those it refutes
// (supported_large_closures, which adds the edges and optimises); refused, it is remembered, and
// goes in later with the large corrections that agree with it.
int GraphSlam::add_closures(const std::vector<LoopClosure>& closures, bool final) {
  const auto checked = [&](const LoopClosure& closure) {
    return config_.check_large_closures && !closure.near() && !closure.edge.robust;
  };
  std::vector<LoopClosure> large;
  std::copy_if(closures.begin(), closures.end(), std::back_inserter(large), checked);
  if (std::any_of(large.begin(), large.end(), [&](const LoopClosure& closure) { return contradicted(closure); })) {
    ++stats_.contradicted_large_closures;  // a confirmed pair the old map's free space refutes
    std::vector<LoopClosure> kept;
    std::copy_if(closures.begin(), closures.end(), std::back_inserter(kept), [&](const LoopClosure& c) { return !checked(c); });
    return add_closures(kept, final);
  }
  const std::vector<LoopClosure> large_added = large.empty() ? large : supported_large_closures(large);
  const bool new_large_added = !large_added.empty();
  // The remembered ones that went in with them follow the new ones (none when those were refused).
  const std::span<const LoopClosure> remembered_added =
      new_large_added ? std::span<const LoopClosure>(large_added).subspan(large.size()) : std::span<const LoopClosure>();
  for (const LoopClosure& closure : remembered_added) record_closure(closure, false);
  bool loop_closed = false;
  bool new_loop = false;
  for (const LoopClosure& closure : closures) {
    if (checked(closure) && !new_large_added) continue;
    if (!checked(closure)) {
      if (!closure.near() && (config_.defer_agreeing_closures || config_.local_reach > 0.0)) {
        // The cycle the edge closes: a new loop beyond link_reach(), optimised locally within local_reach.
        const double cycle = cycle_length(closure.edge, std::max(link_reach(), config_.local_reach));
        new_loop = new_loop || !(cycle <= link_reach());
        pending_cycle_ = std::max(pending_cycle_, cycle <= config_.local_reach ? cycle : std::numeric_limits<double>::infinity());
      }
      graph_.edges.push_back(closure.edge);
      loop_closed = loop_closed || !closure.near();
    }
    record_closure(closure, final);
  }
  if (loop_closed) {
    if (config_.defer_agreeing_closures && !new_loop && !estimate_disagrees()) {
      ++stats_.deferred_optimizations;
    } else if (config_.local_reach > 0.0 && pending_cycle_ <= config_.local_reach) {
      optimize_locally(pending_cycle_);
    } else {
      optimize(config_.run_relative_tolerance);
    }
  }
  if (lifelong()) {
    for (const LoopClosure& closure : closures) recheck_near(closure.keyframe);
    for (const LoopClosure& closure : remembered_added) recheck_near(closure.keyframe);
  }
  return static_cast<int>(closures.size());
}

// Whether the map before a large correction contradicts the recent keyframes moved by it
// (loop_closure.large.max_contradiction): their walls (end points) moved by the correction against an
// occupancy grid of the keyframes within verify_radius of the match up to the chain's end.
bool GraphSlam::contradicted(const LoopClosure& closure) const {
  const LargeClosureConfig& c = config_.loop_closure.large;
  if (c.max_contradiction >= 1.0) return false;
  const Keyframe& current = keyframes_[closure.keyframe];
  const SE2 correction = closure.T_map_matched * graph_.poses[current.node].inverse();
  // Recent: back along the path from the keyframe, to the last gap or verify_radius.
  std::vector<Point2> recent;
  std::size_t first_recent = closure.keyframe + 1;
  while (first_recent > 0 && current.path_distance - keyframes_[first_recent - 1].path_distance <= c.verify_radius) {
    --first_recent;
    const Keyframe& k = keyframes_[first_recent];
    const SE2 moved = correction * graph_.poses[k.node];
    for (const Point2& p : k.cloud.points) recent.push_back(moved * p);
    if (k.after_gap) break;
  }
  // Old: the keyframes before the recent ones, up to the chain's end, near the match.
  OccupancyGrid before(OccupancyGridConfig{.resolution = config_.map_resolution, .max_range = config_.max_range});
  const std::size_t end = std::min(closure.chain_end, first_recent);
  for (std::size_t i = 0; i < end; ++i) {
    const SE2& pose = graph_.poses[keyframes_[i].node];
    if (keyframes_[i].released || (pose.translation() - closure.T_map_matched.translation()).norm() > c.verify_radius) continue;
    before.integrate_scan(keyframe_scans_[i], pose);
  }
  const PointCloud2 wall_cloud = wall_points(before);
  const KdTree2 walls(wall_cloud.points);  // indexes the points in place
  return check_free_space(before, walls, recent, c.verify_distance).contradicted(c.max_contradiction);
}

// A closure that went in: its anchor kept on its keyframe (what the lifelong budget's release
// checks), and counted (a closure of the final search as such too).
void GraphSlam::record_closure(const LoopClosure& closure, bool final) {
  keyframes_[closure.keyframe].loop_anchors.push_back(closure.anchor);
  if (closure.near()) {
    ++stats_.near_links;
    return;
  }
  ++stats_.loop_closures;
  if (final) ++stats_.final_search_closures;
}

// A large correction goes in without the robust kernel, so a wrong one (a repeated structure
// matched the same wrong way twice) bends the map by metres, and the loop edges already there give
// way under their kernel. As in PCM, the larger mutually consistent set of closures wins: the graph
// is optimised without it (when closures wait), then with it and the large corrections refused
// before (they agree with it when the optimum keeps both their edges within the gate; those that do
// not are taken out and it is optimised again). A loop edge within the gate (e^T Omega e within
// chi-square's quantile, 3 dof, at optimize_gate_z) at the first optimum and beyond it at the second
// refutes it. When the refuting edges outnumber the agreeing large corrections' edges, the new one
// is refused and remembered (the last kRememberedRefusals), its edges leave and the poses return to
// the first optimum. Returns the closures that went in: the new ones first, then the remembered.
std::vector<LoopClosure> GraphSlam::supported_large_closures(const std::vector<LoopClosure>& large) {
  apply_merges();  // the edges below `edges` keep their places
  if (first_unoptimized_edge_ < graph_.edges.size()) optimize(config_.run_relative_tolerance);
  const double gate = chi_square_quantile(3.0, config_.optimize_gate_z);
  const std::size_t edges = graph_.edges.size();
  std::vector<std::size_t> agreeing;  // the loop edges within the gate at the first optimum
  for (std::size_t k = 0; k < edges; ++k) {
    const PoseGraphEdge& edge = graph_.edges[k];
    if (loop_edge(edge) && squared_error(edge, graph_.poses) <= gate) agreeing.push_back(k);
  }
  const std::vector<SE2> poses = graph_.poses;
  std::vector<bool> supporting(refused_large_.size(), true);  // the remembered pairs tried with it
  const auto optimize_with = [&] {
    graph_.edges.resize(edges);
    graph_.poses = poses;
    for (const LoopClosure& closure : large) graph_.edges.push_back(closure.edge);
    for (std::size_t r = 0; r < refused_large_.size(); ++r) {
      if (!supporting[r]) continue;
      for (const LoopClosure& closure : refused_large_[r]) graph_.edges.push_back(closure.edge);
    }
    optimize(config_.back_end.relative_tolerance);  // it moves poses by metres: to convergence
  };
  optimize_with();
  bool dropped = false;
  for (std::size_t r = 0; r < refused_large_.size(); ++r) {
    supporting[r] = std::all_of(refused_large_[r].begin(), refused_large_[r].end(), [&](const LoopClosure& closure) {
      return squared_error(closure.edge, graph_.poses) <= gate;
    });
    dropped = dropped || !supporting[r];
  }
  if (dropped) optimize_with();
  std::size_t support = large.size();
  for (std::size_t r = 0; r < refused_large_.size(); ++r) support += supporting[r] ? refused_large_[r].size() : 0;
  const auto refuted = static_cast<std::size_t>(std::count_if(
      agreeing.begin(), agreeing.end(), [&](std::size_t k) { return squared_error(graph_.edges[k], graph_.poses) > gate; }));
  std::vector<LoopClosure> added;
  if (refuted <= support) {
    added = large;
    std::vector<std::vector<LoopClosure>> still_refused;
    for (std::size_t r = 0; r < refused_large_.size(); ++r) {
      if (!supporting[r]) {
        still_refused.push_back(std::move(refused_large_[r]));
        continue;
      }
      added.insert(added.end(), refused_large_[r].begin(), refused_large_[r].end());
      --stats_.rejected_large_closures;
      if (found_globally(refused_large_[r])) --refused_global_closures_;
    }
    refused_large_ = std::move(still_refused);
    return added;
  }
  graph_.edges.resize(edges);
  graph_.poses = poses;
  first_unoptimized_edge_ = edges;
  refused_large_.push_back(large);
  if (refused_large_.size() > kRememberedRefusals) refused_large_.erase(refused_large_.begin());
  ++stats_.rejected_large_closures;
  if (found_globally(large)) ++refused_global_closures_;
  return added;
}

namespace {

// The keyframes [begin, end) whose path distance lies in [from, to] (it grows with the index).
std::pair<std::size_t, std::size_t> along_path(const std::vector<Keyframe>& keyframes, double from, double to) {
  const auto first = std::lower_bound(keyframes.begin(), keyframes.end(), from,
                                      [](const Keyframe& k, double distance) { return k.path_distance < distance; });
  const auto last = std::upper_bound(first, keyframes.end(), to,
                                     [](double distance, const Keyframe& k) { return distance < k.path_distance; });
  return {static_cast<std::size_t>(first - keyframes.begin()), static_cast<std::size_t>(last - keyframes.begin())};
}

}  // namespace

// Lifelong: each keyframe is checked once the loop closer is done with it: it searched the large
// window or the interval skipped it (finish() searches only from later ones), and it lies farther
// back than a large correction's confirmation reaches (confirm_before matches earlier keyframes'
// points). A closure found later may still release it (recheck_near).
void GraphSlam::release_redundant() {
  const double now = keyframes_.back().path_distance;
  const double confirm_reach = config_.loop_closure.large.confirm_max_distance;
  while (release_checked_ < loop_closer_.first_unsearched() &&
         now - keyframes_[release_checked_].path_distance > confirm_reach) {
    try_release(release_checked_++);
  }
}

// A closure from `keyframe`: the checked keyframes around it along the path may now be linked to
// the place it closed on (delayed closures go in when the robot has left the chain).
void GraphSlam::recheck_near(std::size_t keyframe) {
  const double here = keyframes_[keyframe].path_distance;
  const double reach = link_reach();
  const auto [begin, end] = along_path(keyframes_, here - reach, here + reach);
  for (std::size_t k = begin; k < std::min(end, release_checked_); ++k) try_release(k);
}

// The keyframe drops its points and scan when a loop edge of a keyframe near it along the path
// links it to an older keyframe that keeps its own and is redundant with it. That one keeps its
// data for good, so that releases do not chain away from the place.
void GraphSlam::try_release(std::size_t keyframe) {
  if (keyframes_[keyframe].released || keyframes_[keyframe].witness) return;
  const double here = keyframes_[keyframe].path_distance;
  const double reach = link_reach();
  const auto [begin, end] = along_path(keyframes_, here - reach, here + reach);
  for (std::size_t linked = begin; linked < end; ++linked) {
    for (const std::size_t anchor : keyframes_[linked].loop_anchors) {
      const std::optional<std::size_t> witness = linked_witness(keyframe, linked, anchor);
      if (!witness) continue;
      keyframes_[keyframe].released = true;
      keyframes_[keyframe].cloud = {};
      keyframe_scans_[keyframe] = {};
      keyframes_[*witness].witness = true;
      ++stats_.released_keyframes;
      if (config_.keyframes.merge_released) pending_merges_.push_back({keyframes_[keyframe].node, keyframes_[*witness].node});
      return;
    }
  }
}

// An older keyframe that keeps its data, redundant with `keyframe`, that the loop edge from
// `anchor` to `linked` joins to it by a path (along the keyframe's visit, the edge, the anchor's
// visit) of at most link_reach(): the graph holds the two together.
std::optional<std::size_t> GraphSlam::linked_witness(std::size_t keyframe, std::size_t linked,
                                                     std::size_t anchor) const {
  const auto position = [&](std::size_t k) { return graph_.poses[keyframes_[k].node].translation(); };
  const double budget = link_reach() -
                        std::abs(keyframes_[linked].path_distance - keyframes_[keyframe].path_distance) -
                        (position(linked) - position(anchor)).norm();
  if (budget < 0.0) return std::nullopt;
  const double there = keyframes_[anchor].path_distance;
  const auto [begin, end] = along_path(keyframes_, there - budget, there + budget);
  for (std::size_t k = begin; k < std::min(end, keyframe); ++k) {
    if (!keyframes_[k].released && redundant(keyframe, k)) return k;
  }
  return std::nullopt;
}

bool GraphSlam::redundant(std::size_t keyframe, std::size_t older) const {
  const SE2 apart = graph_.poses[keyframes_[older].node].between(graph_.poses[keyframes_[keyframe].node]);
  return apart.translation().norm() <= config_.keyframes.redundant_radius &&
         std::abs(apart.theta()) <= config_.keyframes.redundant_angle;
}

int GraphSlam::close_loops(std::size_t current, bool final) {
  const auto started = std::chrono::steady_clock::now();
  const std::vector<LoopClosure> closures = loop_closer_.close(keyframes_, graph_, current, final);
  stats_.loop_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const int added = add_closures(closures, final);
  copy_loop_stats();
  return added;
}

void GraphSlam::copy_loop_stats() {
  const LoopCloserStats& loops = loop_closer_.stats();
  stats_.loop_attempts = loops.attempts;
  stats_.global_searches = loops.global_searches;
  stats_.global_closures = loops.global_closures - refused_global_closures_;
  stats_.large_closures = loops.large_closures - stats_.rejected_large_closures;
  stats_.unconfirmed_closures = loops.unconfirmed;
  stats_.global_search_seconds = loops.global_seconds;
  stats_.held_replaced = loops.held_replaced;
  stats_.held_dropped = loops.held_dropped;
}

// The shortest path along the graph's edges between the edge's two nodes (the cycle the edge
// closes), in metres; infinite beyond `reach`.
double GraphSlam::cycle_length(const PoseGraphEdge& edge, double reach) const {
  const std::vector<std::optional<GraphPath>> gaps = gap_steps(keyframes_, graph_.size(), config_.loop_closure.drift);
  const std::vector<GraphPath> paths = graph_paths(graph_, static_cast<std::size_t>(edge.to), reach, &gaps);
  return paths[static_cast<std::size_t>(edge.from)].distance;
}

// Whether the loop edges added since the last optimisation disagree with the current poses beyond
// their own noise (defer_agreeing_closures).
bool GraphSlam::estimate_disagrees() const {
  double sum = 0.0;
  double loop_edges = 0.0;
  for (std::size_t k = first_unoptimized_edge_; k < graph_.edges.size(); ++k) {
    const PoseGraphEdge& edge = graph_.edges[k];
    if (loop_edge(edge)) {
      sum += squared_error(edge, graph_.poses);
      loop_edges += 1.0;
    }
  }
  return loop_edges > 0.0 && sum > chi_square_quantile(3.0 * loop_edges, config_.optimize_gate_z);
}

void GraphSlam::optimize(double relative_tolerance) {
  first_unoptimized_edge_ = graph_.edges.size();
  pending_cycle_ = 0.0;
  const SparsePoseAdjustmentResult result = back_end_.optimize(graph_, relative_tolerance);
  follow_merges();
  apply_merges();  // at the poses just optimised
  stats_.optimization_seconds += result.seconds;
  ++stats_.optimizations;
  stats_.optimization_iterations += static_cast<std::size_t>(result.iterations);
}

// Merged nodes (keyframes.merge_released): a released keyframe's node joins its witness's, at the
// pose it has from it now (X_node = X_into D). Every edge at the node moves to the witness: from
// the node, the measurement becomes D Z (the same error); to it, Z D^-1, whose error is the old one
// carried by Ad(D^-1), so its information is Ad(D^-1)^T Omega Ad(D^-1). D is no measurement but
// the estimate, so each moved end adds the loop closures' floor (loop_closure.match's
// min_sigma_translation / min_sigma_rotation) to the edge's covariance. An edge between the node
// and its witness (or another node merged there) joins a node to itself and goes. The merged node
// keeps its index, without an edge (the back end leaves it out), and its pose follows the
// witness's (follow_merges): the scans and the map read it as before.
void GraphSlam::apply_merges() {
  if (pending_merges_.empty() && stats_.merged_nodes == 0) return;
  merged_.resize(graph_.poses.size());
  for (const auto& [node, into] : pending_merges_) {
    merged_[node] = NodeMerge{.into = into, .T_into_node = graph_.poses[into].between(graph_.poses[node])};
    ++stats_.merged_nodes;
  }
  pending_merges_.clear();
  const MapMatchConfig& floor = config_.loop_closure.match;
  const Covariance3 uncertainty =
      covariance_from_sigmas(floor.min_sigma_translation, floor.min_sigma_translation, floor.min_sigma_rotation);
  const auto widen = [&](Eigen::Matrix3d& information) {
    const Eigen::Matrix3d widened = information * (Eigen::Matrix3d::Identity() + uncertainty * information).inverse();
    information = 0.5 * (widened + widened.transpose());
  };
  std::size_t kept = 0;
  std::size_t unoptimized = first_unoptimized_edge_;
  for (std::size_t k = 0; k < graph_.edges.size(); ++k) {
    PoseGraphEdge edge = graph_.edges[k];
    if (const std::optional<NodeMerge>& merge = merged_[static_cast<std::size_t>(edge.from)]) {
      edge.from = static_cast<int>(merge->into);
      edge.T_from_to = merge->T_into_node * edge.T_from_to;
      widen(edge.information);
    }
    if (const std::optional<NodeMerge>& merge = merged_[static_cast<std::size_t>(edge.to)]) {
      const Eigen::Matrix3d A = merge->T_into_node.inverse().adjoint();
      edge.to = static_cast<int>(merge->into);
      edge.T_from_to = edge.T_from_to * merge->T_into_node.inverse();
      edge.information = A.transpose() * edge.information * A;
      widen(edge.information);
    }
    if (edge.from == edge.to) {
      if (k < first_unoptimized_edge_) --unoptimized;
      continue;
    }
    graph_.edges[kept++] = edge;
  }
  graph_.edges.resize(kept);
  first_unoptimized_edge_ = unoptimized;
}

// The merged nodes' poses from their witnesses' (after the back end moved them).
void GraphSlam::follow_merges() {
  for (std::size_t node = 0; node < merged_.size(); ++node) {
    if (const std::optional<NodeMerge>& merge = merged_[node]) graph_.poses[node] = graph_.poses[merge->into] * merge->T_into_node;
  }
}

// An optimisation of the closures' neighbourhood (local_reach): the nodes within `radius` (the
// longest cycle the loop edges not yet optimised close, at least kMinLocalRadius) along the
// graph's edges of those edges' ends are free, every cycle's nodes among them, the others fixed;
// the whole graph when that frees every node.
void GraphSlam::optimize_locally(double radius) {
  constexpr double kMinLocalRadius = 5.0;  // m
  radius = std::max(radius, kMinLocalRadius);
  const std::vector<std::optional<GraphPath>> gaps = gap_steps(keyframes_, graph_.size(), config_.loop_closure.drift);
  std::vector<std::size_t> ends;
  for (std::size_t k = first_unoptimized_edge_; k < graph_.edges.size(); ++k) {
    const PoseGraphEdge& edge = graph_.edges[k];
    if (!loop_edge(edge)) continue;
    ends.push_back(static_cast<std::size_t>(edge.from));
    ends.push_back(static_cast<std::size_t>(edge.to));
  }
  std::vector<bool> fixed = nodes_within_graph_distance(graph_, ends, radius, &gaps);
  fixed.flip();  // within reach of an end: free
  if (std::find(fixed.begin(), fixed.end(), true) == fixed.end()) {
    optimize(config_.run_relative_tolerance);
    return;
  }
  graph_.fixed = std::move(fixed);
  optimize(config_.run_relative_tolerance);
  graph_.fixed.clear();
  ++stats_.local_optimizations;
}

void GraphSlam::finish() {
  for (std::size_t k = loop_closer_.first_unsearched(); k < keyframes_.size(); ++k) close_loops(k, true);
  add_closures(loop_closer_.release(), true);
  copy_loop_stats();
  if (graph_.poses.size() > 1) optimize(config_.back_end.relative_tolerance);
}

// A scan between keyframes a and b: its tracked motion from a carried forward from a's optimised
// pose and backward from b's (pose_between_anchors), so the chain of scans meets both optimised ends.
SE2 GraphSlam::interpolated_pose(const ScanRecord& record) const {
  const SE2& T_map_a = graph_.poses[keyframes_[record.keyframe].node];
  if (record.keyframe + 1 >= keyframes_.size()) return T_map_a * record.T_keyframe_robot;
  const SE2& T_map_b = graph_.poses[keyframes_[record.keyframe + 1].node];
  return pose_between_anchors(T_map_a, T_map_b, keyframe_motion_[record.keyframe + 1], record.T_keyframe_robot);
}

Trajectory GraphSlam::trajectory() const {
  Trajectory trajectory;
  trajectory.reserve(scans_.size());
  for (const ScanRecord& record : scans_) trajectory.push_back(record.stamp, interpolated_pose(record));
  return trajectory;
}

OccupancyMap GraphSlam::map() const {
  OccupancyGrid grid(OccupancyGridConfig{.resolution = config_.map_resolution, .max_range = config_.max_range});
  for (std::size_t k = 0; k < keyframes_.size(); ++k) {
    if (keyframes_[k].released) continue;  // its place is drawn by the keyframe that witnessed the release
    grid.integrate_scan(keyframe_scans_[k], graph_.poses[keyframes_[k].node]);
  }
  return grid.to_occupancy_map();
}

}  // namespace slam2d
