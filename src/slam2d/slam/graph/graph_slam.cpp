#include "slam2d/slam/graph/graph_slam.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/normals.hpp"
#include "slam2d/slam/hector/scan_preprocessing.hpp"

namespace slam2d {

void validate(const GraphSlamConfig& config) {
  check(std::isfinite(config.min_range) && config.min_range >= 0.0, "graph slam: min_range must be >= 0");
  check(std::isfinite(config.max_range) && config.max_range > config.min_range,
        "graph slam: max_range must be > min_range");
  validate(config.keyframes);
  validate(config.sequential);
  validate(config.loop_closure);
  validate(config.back_end);
  check(std::isfinite(config.map_resolution) && config.map_resolution > 0.0, "graph slam: map_resolution must be > 0");
  check(std::isfinite(config.max_prior_dt) && config.max_prior_dt >= 0.0, "graph slam: max_prior_dt must be >= 0");
  check(std::isfinite(config.unmatched_sigma_translation) && config.unmatched_sigma_translation > 0.0,
        "graph slam: unmatched_sigma_translation must be > 0");
  check(std::isfinite(config.unmatched_sigma_rotation) && config.unmatched_sigma_rotation > 0.0,
        "graph slam: unmatched_sigma_rotation must be > 0");
  const OdometryNoise& noise = config.odometry_noise;
  check(noise.translation_floor > 0.0 && noise.rotation_floor > 0.0, "graph slam: odometry noise floors must be > 0");
  check(noise.translation_per_metre >= 0.0 && noise.rotation_per_radian >= 0.0 && noise.rotation_per_metre >= 0.0,
        "graph slam: odometry noise slopes must be >= 0");
}

Covariance3 odometry_covariance(const SE2& motion, const OdometryNoise& noise) {
  const double distance = motion.translation().norm();
  const double sigma_translation = noise.translation_floor + noise.translation_per_metre * distance;
  const double sigma_rotation = noise.rotation_floor + noise.rotation_per_radian * std::abs(motion.theta()) +
                                noise.rotation_per_metre * distance;
  return covariance_from_sigmas(sigma_translation, sigma_translation, sigma_rotation);
}

ScanToMapResult fuse_with_prediction(const ScanToMapResult& match, const SE2& prediction,
                                     const Covariance3& prediction_covariance) {
  // In the prediction's frame: the prediction is 0, the match is delta with its covariance rotated in.
  const Eigen::Vector3d delta = prediction.between(match.T_map_robot).vector();
  const Eigen::Matrix3d match_information =
      information_from_covariance(rotate_covariance(match.covariance, -prediction.theta()));
  const Eigen::Matrix3d fused_information = match_information + information_from_covariance(prediction_covariance);
  const Covariance3 fused_covariance = fused_information.inverse();
  ScanToMapResult fused = match;
  fused.T_map_robot = prediction * SE2::from_vector(fused_covariance * match_information * delta);
  fused.covariance = rotate_covariance(0.5 * (fused_covariance + fused_covariance.transpose()), prediction.theta());
  return fused;
}

GraphSlam::GraphSlam(const GraphSlamConfig& config)
    : config_(config), selector_(config.keyframes), back_end_(config.back_end), loop_closer_(config.loop_closure) {
  validate(config_);
}

SE2 GraphSlam::current_pose() const {
  if (scans_.empty()) return SE2();
  const ScanRecord& last = scans_.back();
  return graph_.poses[keyframes_[last.keyframe].node] * last.T_keyframe_robot;
}

SE2 GraphSlam::predict(const LaserScan& scan, const std::optional<SE2>& T_odom_robot) const {
  const SE2 last = current_pose();
  if (T_odom_robot && last_odom_) return last * last_odom_->between(*T_odom_robot);
  const double dt = scan.stamp - last_stamp_;
  if (!velocity_ || dt <= 0.0 || dt > config_.max_prior_dt) return last;
  return last * SE2::exp(dt * velocity_->log());
}

PointCloud2 GraphSlam::scan_cloud(const LaserScan& scan) const {
  PointCloud2 cloud;
  cloud.points = usable_end_points(scan, config_.min_range, config_.max_range);
  estimate_normals_ordered(cloud);
  return cloud;
}

// The local map: the most recent keyframes within buffer_distance of travel (Karto's running
// scans), cropped around the last keyframe; rebuilt only when a keyframe or the graph changed.
const MatchMap& GraphSlam::local_map() {
  if (local_map_stale_) {
    rebuild_local_map();
    local_map_stale_ = false;
  }
  return local_map_;
}

ScanToMapResult GraphSlam::match_local_map(const PointCloud2& cloud, const SE2& guess) {
  return match_scan_to_map(local_map(), cloud, guess, config_.sequential.match);
}

// A scan between keyframes: the odometry prediction refined against the local map.
SE2 GraphSlam::track(const PointCloud2& cloud, const SE2& prediction) {
  const MatchMap& map = local_map();
  if (map.cloud.size() < 3 || cloud.size() < 3) return prediction;
  const MapMatchConfig& config = config_.sequential.match;
  const MatchResult fine = match_point_to_plane(map.grid.tree(), map.cloud, cloud, prediction, config.refinement);
  const SE2 shift = prediction.between(fine.T_target_source);
  const bool plausible = shift.translation().norm() <= config.max_refinement_shift &&
                         std::abs(shift.theta()) <= config.correlative.window_theta;
  return fine.converged && plausible ? fine.T_target_source : prediction;
}

void GraphSlam::rebuild_local_map() {
  std::vector<const Keyframe*> members;
  std::vector<SE2> poses;
  const double path_end = keyframes_.back().path_distance;
  for (std::size_t k = keyframes_.size(); k-- > 0;) {
    if (static_cast<int>(members.size()) >= config_.sequential.buffer_size) break;
    if (path_end - keyframes_[k].path_distance > config_.sequential.buffer_distance) break;
    members.push_back(&keyframes_[k]);
    poses.push_back(graph_.poses[keyframes_[k].node]);
  }
  const Eigen::Vector2d center = graph_.poses[keyframes_.back().node].translation();
  const MapMatchConfig& match = config_.sequential.match;
  local_map_ = make_match_map(map_cloud(members, poses, center, config_.sequential.map_radius, match.map_voxel), match);
}

GraphSlamStep GraphSlam::add_scan(const LaserScan& scan, const std::optional<SE2>& T_odom_robot) {
  GraphSlamStep step;
  const SE2 previous = current_pose();
  const SE2 prediction = predict(scan, T_odom_robot);
  const bool first = keyframes_.empty();
  PointCloud2 cloud = scan_cloud(scan);
  ScanToMapResult match;
  // With odometry the prediction may be refined (tracking); a scan that is then a keyframe
  // candidate is matched with the search. Without odometry every scan is searched: its match is
  // the only measure of where it is.
  SE2 guess = prediction;
  if (!first && T_odom_robot && config_.sequential.track_every_scan) guess = track(cloud, prediction);
  match.T_map_robot = guess;
  if (!first && (!T_odom_robot || selector_.is_keyframe(guess, scan.stamp))) {
    match = match_local_map(cloud, guess);
    if (!match.converged) match.T_map_robot = guess;
    if (match.converged && T_odom_robot) {
      const SE2 motion = graph_.poses[keyframes_.back().node].between(guess);
      match = fuse_with_prediction(match, guess, odometry_covariance(motion, config_.odometry_noise));
    }
  }
  const SE2 estimate = match.T_map_robot;
  if (first || selector_.is_keyframe(estimate, scan.stamp)) {
    add_keyframe(scan, std::move(cloud), guess, match);
    step.keyframe = true;
    step.matched = match.converged;
    step.loop_closures = close_loops();
  } else {
    const std::size_t keyframe = keyframes_.size() - 1;
    scans_.push_back({scan.stamp, keyframe, graph_.poses[keyframes_[keyframe].node].between(estimate)});
  }
  const double dt = scan.stamp - last_stamp_;
  if (!first && dt > 0.0 && step.loop_closures == 0) velocity_ = SE2::exp(previous.between(current_pose()).log() / dt);
  last_odom_ = T_odom_robot;
  last_stamp_ = scan.stamp;
  ++stats_.scans;
  step.T_map_robot = current_pose();
  return step;
}

void GraphSlam::add_keyframe(const LaserScan& scan, PointCloud2 cloud, const SE2& prediction,
                             const ScanToMapResult& match) {
  const bool first = keyframes_.empty();
  Keyframe keyframe;
  keyframe.node = graph_.poses.size();
  keyframe.scan = stats_.scans;
  keyframe.stamp = scan.stamp;
  keyframe.cloud = std::move(cloud);
  const SE2 estimate = first ? SE2() : match.T_map_robot;
  if (!first) {
    const Keyframe& previous = keyframes_.back();
    const SE2& T_map_previous = graph_.poses[previous.node];
    keyframe.path_distance = previous.path_distance + (estimate.translation() - T_map_previous.translation()).norm();
    PoseGraphEdge edge;
    edge.from = static_cast<int>(previous.node);
    edge.to = static_cast<int>(keyframe.node);
    edge.T_from_to = T_map_previous.between(estimate);
    const Covariance3 covariance =
        match.converged ? rotate_covariance(match.covariance, -T_map_previous.theta())
                        : covariance_from_sigmas(config_.unmatched_sigma_translation, config_.unmatched_sigma_translation,
                                                 config_.unmatched_sigma_rotation);
    edge.information = information_from_covariance(covariance);
    graph_.edges.push_back(edge);
    uncertainty_variance_ += covariance(0, 0) + covariance(1, 1);
    keyframe_motion_.push_back(T_map_previous.between(prediction));
    if (!match.converged) ++stats_.sequential_failures;
  } else {
    keyframe_motion_.push_back(SE2());
  }
  graph_.poses.push_back(estimate);
  selector_.accept(estimate, scan.stamp);
  scans_.push_back({scan.stamp, keyframes_.size(), SE2()});
  keyframes_.push_back(std::move(keyframe));
  keyframe_scans_.push_back(scan);
  local_map_stale_ = true;
  ++stats_.keyframes;
}

void GraphSlam::add_closure(const LoopClosure& closure) {
  graph_.edges.push_back(closure.edge);
  ++(closure.near ? stats_.near_links : stats_.loop_closures);
}

int GraphSlam::close_loops() {
  const double radius = config_.loop_closure.uncertainty_sigmas * std::sqrt(uncertainty_variance_);
  const std::vector<LoopClosure> closures =
      loop_closer_.close(keyframes_, graph_, keyframes_.size() - 1, radius, &stats_.loop_attempts);
  bool loop_closed = false;
  for (const LoopClosure& closure : closures) {
    add_closure(closure);
    loop_closed = loop_closed || !closure.near;
  }
  if (loop_closed) {
    optimize();
    uncertainty_variance_ = 0.0;
  }
  return static_cast<int>(closures.size());
}

void GraphSlam::optimize() {
  const SparsePoseAdjustmentResult result = back_end_.optimize(graph_);
  stats_.optimization_seconds += result.seconds;
  local_map_stale_ = true;
  ++stats_.optimizations;
}

void GraphSlam::finish() {
  if (const auto pending = loop_closer_.release()) add_closure(*pending);
  if (graph_.poses.size() > 1) optimize();
}

// A scan between keyframes a and b: its motion from a (odometry, or its match) carried forward
// from a's optimised pose and backward from b's, blended by how far along the motion from a to b
// it is, so the chain of scans meets both optimised ends.
SE2 GraphSlam::interpolated_pose(const ScanRecord& record) const {
  const SE2& T_map_a = graph_.poses[keyframes_[record.keyframe].node];
  const SE2 forward = T_map_a * record.T_keyframe_robot;
  if (record.keyframe + 1 >= keyframes_.size()) return forward;
  const SE2& T_map_b = graph_.poses[keyframes_[record.keyframe + 1].node];
  const SE2& motion_ab = keyframe_motion_[record.keyframe + 1];
  const SE2 backward = T_map_b * motion_ab.between(record.T_keyframe_robot);
  constexpr double kMetresPerRadian = 1.0;
  const auto extent = [&](const SE2& motion) {
    return motion.translation().norm() + kMetresPerRadian * std::abs(motion.theta());
  };
  const double total = extent(motion_ab);
  const double fraction = total > 1e-9 ? std::clamp(extent(record.T_keyframe_robot) / total, 0.0, 1.0) : 0.0;
  return interpolate(forward, backward, fraction);
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
    grid.integrate_scan(keyframe_scans_[k], graph_.poses[keyframes_[k].node]);
  }
  return grid.to_occupancy_map();
}

}  // namespace slam2d
