// SPDX-License-Identifier: BSD-3-Clause
// Scan-to-scan odometry with keyframes (CSM's ROS laser_scan_matcher); see scan_odometry.hpp.

#include "slam2d/registration/scan_odometry.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry.hpp"

namespace slam2d {

void validate(const ScanOdometryConfig& config) {
  check_fields(config, "ScanOdometryConfig");
  check(config.max_range > config.min_range, "ScanOdometryConfig: max_range must be > min_range");
}

MatchResult match_between_robots(const MatchResult& match, const SE2& T_robot_target_sensor,
                                 const SE2& T_robot_source_sensor) {
  const SE2 C = T_robot_source_sensor.inverse();
  MatchResult moved = match;
  moved.T_target_source = T_robot_target_sensor * match.T_target_source * C;
  // (x, y) = t_A + R_A (t_T + R_T t_C), theta = theta_A + theta_T + theta_C.
  const Eigen::Matrix2d R_A = T_robot_target_sensor.rotation();
  const Point2 lever = match.T_target_source.rotation() * C.translation();
  Matrix3 J = Matrix3::Identity();
  J.topLeftCorner<2, 2>() = R_A;
  J.topRightCorner<2, 1>() = R_A * Point2(-lever.y(), lever.x());
  if (match.covariance.diagonal().minCoeff() < kUnknownVariance) moved.covariance = propagate(match.covariance, J);
  const Eigen::Vector3d weak = J * match.weak_direction;
  if (weak.norm() > 0.0) moved.weak_direction = weak.normalized();
  return moved;
}

ScanOdometry::ScanOdometry(Matcher matcher, const ScanOdometryConfig& config)
    : matcher_(std::move(matcher)),
      config_(config),
      odometry_guard_(config.odometry_guard),
      odometry_noise_(config.odometry_noise) {
  check(static_cast<bool>(matcher_), "scan odometry: no matcher given");
  validate(config_);
}

PointCloud2 ScanOdometry::usable_cloud(const LaserScan& scan) const {
  PointCloud2 cloud = to_point_cloud(scan, ScanFrame::kSensor).cloud;
  std::size_t kept = 0;
  for (const Point2& p : cloud.points) {
    const double range = p.norm();
    if (range >= config_.min_range && range < config_.max_range) cloud.points[kept++] = p;
  }
  cloud.points.resize(kept);
  cloud.normals.clear();
  cloud.weights.clear();
  return cloud;
}

// The new keyframe, and the local map the next scans are matched against: its cloud followed by
// those of the keyframes before it (at most local_map_keyframes in all), each moved into its sensor
// frame by the poses estimated for them. A keyframe taken because the last one no longer
// matched starts the local map afresh.
void ScanOdometry::take_keyframe(Keyframe keyframe, bool keep_local_map) {
  if (keyframe_ && keep_local_map && config_.local_map_keyframes > 1) {
    earlier_keyframes_.push_front(std::move(*keyframe_));
    earlier_keyframes_.resize(std::min(earlier_keyframes_.size(), config_.local_map_keyframes - 1));
  } else {
    earlier_keyframes_.clear();
  }
  keyframe_ = std::move(keyframe);
  ++stats_.keyframes;
  target_ = keyframe_->cloud;
  const SE2 T_sensor_world = (keyframe_->T_world_robot * keyframe_->T_robot_sensor).inverse();
  for (const Keyframe& earlier : earlier_keyframes_) {
    const PointCloud2 moved = transform(earlier.cloud, T_sensor_world * earlier.T_world_robot * earlier.T_robot_sensor);
    target_.points.insert(target_.points.end(), moved.points.begin(), moved.points.end());
  }
}

// The motion from the keyframe to the new scan: odometry when both have it (odom_pose is given
// only when the guard trusts this scan's increment), else constant velocity.
SE2 ScanOdometry::predict(double stamp, const std::optional<SE2>& odom_pose) const {
  if (odom_pose && keyframe_->odom_pose) return keyframe_->odom_pose->between(*odom_pose);
  const SE2 T_keyframe_previous = keyframe_->T_world_robot.between(T_world_previous_);
  const double dt = stamp - previous_stamp_;
  if (!velocity_ || !(dt > 0.0) || dt > config_.max_guess_dt) return T_keyframe_previous;
  return T_keyframe_previous * constant_velocity_motion(*velocity_, dt, velocity_dt_);
}

bool ScanOdometry::passes_gate(const MatchResult& match, const SE2& guess, std::size_t points) const {
  if (config_.require_convergence && !match.converged) return false;
  if (!match.T_target_source.vector().allFinite()) return false;
  if (static_cast<double>(match.inliers) < config_.min_inlier_fraction * static_cast<double>(points)) return false;
  if (!(match.residual <= config_.max_residual)) return false;
  const SE2 correction = guess.between(match.T_target_source);
  return correction.translation().norm() <= config_.max_correction_distance &&
         std::abs(correction.theta()) <= config_.max_correction_angle;
}

// The motion from the keyframe measured twice, by the trusted odometry and by the accepted match
// (moved into the robots' frames with its covariance), fused (core/motion_fusion.hpp); the
// agreement teaches the odometry's noise model its scale.
SE2 ScanOdometry::fuse_with_odometry(const SE2& odometry, const SE2& T_robot_sensor) {
  const MatchResult moved = match_between_robots(last_match_, keyframe_->T_robot_sensor, T_robot_sensor);
  const MotionMeasurement match = match_measurement(moved, config_.match_noise);
  const FusedMotion fused =
      fuse_motion({odometry, odometry_noise_.covariance(odometry)}, match, config_.fusion_gate);
  stats_.fusion.count(fused.outcome);
  if (!moved.degenerate) odometry_noise_.observe(odometry, match.value, match.covariance);
  return fused.value;
}

void ScanOdometry::update_velocity(double stamp, const SE2& T_world_robot) {
  const double dt = stamp - previous_stamp_;
  if (dt > 0.0 && dt <= config_.max_guess_dt) {
    velocity_ = T_world_previous_.between(T_world_robot);
    velocity_dt_ = dt;
  } else {
    velocity_.reset();
  }
  T_world_previous_ = T_world_robot;
  previous_stamp_ = stamp;
}

SE2 ScanOdometry::add(const LaserScan& scan, std::optional<SE2> odom_pose) {
  ++stats_.scans;
  PointCloud2 cloud = usable_cloud(scan);
  // The guarded odometry pose (the odometry with every untrusted increment replaced, below, by
  // the motion the scan is estimated to have made), or none when this increment is not trusted.
  std::optional<SE2> guarded;
  bool odometry_moved = false;
  if (odom_pose) {
    const OdometryCheck odometry = odometry_guard_.check(scan.stamp, *odom_pose);
    odometry_moved = odometry.moved;
    if (odometry.trusted()) guarded = odometry_correction_ ? *odometry_correction_ * *odom_pose : *odom_pose;
    if (odometry.fault == OdometryFault::kCatchUp) {  // the motion since the odometry last moved
      guarded = guarded_moved_ * odometry.increment;
      odometry_correction_ = *guarded * odom_pose->inverse();
    }
  }
  if (!keyframe_) {  // the first scan fixes the world frame
    const SE2 pose = odom_pose.value_or(SE2());
    take_keyframe(Keyframe{std::move(cloud), pose, scan.T_robot_sensor, odom_pose, stats_.scans - 1}, false);
    if (odom_pose) guarded_previous_ = guarded_moved_ = *odom_pose;
    T_world_previous_ = pose;
    previous_stamp_ = scan.stamp;
    trajectory_.push_back(scan.stamp, pose);
    return pose;
  }
  const SE2 guess = predict(scan.stamp, guarded);  // T_keyframe_robot
  SE2 T_keyframe_robot = guess;
  last_accepted_ = false;
  last_matched_ = cloud.size() >= 3;
  if (last_matched_) {
    last_target_T_robot_sensor_ = keyframe_->T_robot_sensor;
    last_target_index_ = keyframe_->index;
    const SE2 guess_sensor = keyframe_->T_robot_sensor.inverse() * guess * scan.T_robot_sensor;
    const auto start = std::chrono::steady_clock::now();
    last_match_ = matcher_(target_, cloud, guess_sensor);
    stats_.matcher_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++stats_.matches;
    stats_.total_iterations += static_cast<std::size_t>(std::max(0, last_match_.iterations));
    last_accepted_ = passes_gate(last_match_, guess_sensor, cloud.size());
    if (last_accepted_) {
      T_keyframe_robot = keyframe_->T_robot_sensor * last_match_.T_target_source * scan.T_robot_sensor.inverse();
      const bool odometry_guess = guarded && keyframe_->odom_pose;
      if (odometry_guess && config_.fuse_odometry) {
        T_keyframe_robot = fuse_with_odometry(guess, scan.T_robot_sensor);
      }
    }
  }
  if (!last_accepted_) ++stats_.failures;
  const SE2 pose = keyframe_->T_world_robot * T_keyframe_robot;
  if (odom_pose && !guarded) {  // the estimated motion stands in for the untrusted increment
    guarded = guarded_previous_ * T_world_previous_.between(pose);
    odometry_correction_ = *guarded * odom_pose->inverse();
  }
  if (guarded) guarded_previous_ = *guarded;
  if (odometry_moved) guarded_moved_ = *guarded;
  update_velocity(scan.stamp, pose);
  trajectory_.push_back(scan.stamp, pose);
  const bool moved = T_keyframe_robot.translation().norm() >= config_.keyframe_distance ||
                     std::abs(T_keyframe_robot.theta()) >= config_.keyframe_angle;
  const bool lost = !last_accepted_ && cloud.size() >= 3;
  if (moved || lost) take_keyframe(Keyframe{std::move(cloud), pose, scan.T_robot_sensor, guarded, stats_.scans - 1}, !lost);
  return pose;
}

}  // namespace slam2d
