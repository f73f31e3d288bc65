// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/ekf.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/localization/sensor_model.hpp"
#include "slam2d/registration/correlative.hpp"

namespace slam2d {

void validate(const EkfConfig& config) {
  check_fields(config, "EkfConfig");
  check(config.max_window_xy >= config.min_window_xy, "EkfConfig: max_window_xy must be >= min_window_xy");
  check(config.max_window_theta >= config.min_window_theta, "EkfConfig: max_window_theta must be >= min_window_theta");
}

EkfLocalization::EkfLocalization(const LocalizationMap& map, const EkfConfig& config)
    : map_(map), config_(config), status_(config.status), motion_noise_(config.motion, config.motion_noise) {
  validate(config_);
  const PointCloud2 obstacles = occupied_points(map_.map(), map_.field().config().occupied_threshold);
  check(!obstacles.empty(), "ekf: the map has no occupied cells to match against");
  // The margin lets the widest window reach past the outermost walls without leaving the table.
  table_ = CorrelativeGrid(obstacles, CorrelativeGridConfig{.resolution = map_.map().resolution,
                                                            .sigma = config_.table_sigma,
                                                            .levels = 6,
                                                            .margin = config_.max_window_xy});
}

void EkfLocalization::initialize(const SE2& T_map_robot, const Covariance3& covariance) {
  check(is_valid_covariance(covariance), "ekf: the initial covariance must be symmetric positive semi-definite");
  pose_ = T_map_robot;
  covariance_ = make_positive_definite(covariance, 1e-10);
  initialized_ = true;
  started_ = false;
  rejections_ = 0;
  status_.reset();
  motion_noise_.restart();
}

bool EkfLocalization::correct(const std::vector<Eigen::Vector2d>& points_robot) {
  ++stats_.updates;
  // Correlative search over +-3 sigma of the prediction, then least-squares refinement.
  const double sigma_xy = std::sqrt(std::max(covariance_(0, 0), covariance_(1, 1)));
  CorrelativeConfig search;
  search.window_x = search.window_y = std::clamp(3.0 * sigma_xy, config_.min_window_xy, config_.max_window_xy);
  search.window_theta = std::clamp(3.0 * std::sqrt(covariance_(2, 2)), config_.min_window_theta, config_.max_window_theta);
  search.angular_step = config_.angular_step;
  search.min_score = 0.0;  // the inlier gate below judges the fit
  PointCloud2 scan;
  scan.points.assign(points_robot.begin(), points_robot.end());
  const MatchResult coarse = match_correlative(table_, scan, pose_, search);
  const MatchResult match = match_likelihood_field(map_.field(), points_robot, coarse.T_target_source, config_.matcher);
  if (match.inlier_fraction < config_.min_inlier_fraction) {
    ++stats_.rejected_match;
    return false;
  }
  const Covariance3 R = coarse.covariance + covariance_from_sigmas(config_.measurement_sigma_xy, config_.measurement_sigma_xy,
                                                                   config_.measurement_sigma_theta);
  Eigen::Vector3d innovation = match.T_target_source.vector() - pose_.vector();
  innovation.z() = angle_difference(match.T_target_source.theta(), pose_.theta());
  const Eigen::Matrix3d S = covariance_ + R;
  if (innovation.dot(S.ldlt().solve(innovation)) > config_.gate_chi2) {  // Mahalanobis gate
    ++stats_.rejected_gate;
    return false;
  }
  // Information form: P+^-1 = P^-1 + R^-1, x+ = x + P+ R^-1 (z - x).
  const Eigen::Matrix3d R_inverse = information_from_covariance(R);
  const Eigen::Matrix3d posterior = (information_from_covariance(covariance_) + R_inverse).inverse();
  const Eigen::Vector3d correction = posterior * R_inverse * innovation;
  pose_ = SE2(pose_.x() + correction.x(), pose_.y() + correction.y(), pose_.theta() + correction.z());
  covariance_ = make_positive_definite(0.5 * (posterior + posterior.transpose()), 1e-10);
  motion_noise_.measured(match.T_target_source, coarse.covariance);
  ++stats_.accepted;
  return true;
}

LocalizationEstimate EkfLocalization::update(const SE2& T_odom_robot, const LaserScan& scan) {
  check(initialized_, "ekf: initialize() before update()");
  if (started_) {
    const SE2 increment = last_odom_.between(T_odom_robot);
    const MotionPrediction prediction = predict_odometry_motion(pose_, covariance_, motion_noise_.move(increment), motion_noise_.model());
    pose_ = prediction.pose;
    covariance_ = prediction.covariance;
  }
  started_ = true;
  last_odom_ = T_odom_robot;
  const ScanBeams beams = select_beams(scan, config_.max_beams, config_.usable_range);
  // Once lost the filter stays lost (it cannot relocalize): it only predicts.
  if (!lost()) {
    const bool accepted = correct(beams.points_robot);
    rejections_ = accepted ? 0 : rejections_ + 1;
    if (!accepted) {
      covariance_ += covariance_from_sigmas(config_.rejection_sigma_xy, config_.rejection_sigma_xy, config_.rejection_sigma_theta);
    }
  }
  LocalizationEstimate estimate;
  estimate.pose = pose_;
  estimate.covariance = covariance_;
  estimate.plausibility = map_.plausibility(beams.points_robot, pose_, config_.status.plausibility_distance);
  estimate.localized = status_.update(covariance_, estimate.plausibility);
  if (rejections_ >= config_.lost_after_rejections) {
    status_.reset();
    estimate.localized = false;
  }
  return estimate;
}

}  // namespace slam2d
