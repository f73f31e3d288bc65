// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/localizer.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "slam2d/core/angles.hpp"

namespace slam2d {

double sigma_xy(const Covariance3& covariance) {
  const Eigen::Matrix2d block = covariance.topLeftCorner<2, 2>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(0.5 * (block + block.transpose()), Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(solver.eigenvalues()(1), 0.0));
}

bool LocalizationStatus::update(const Covariance3& covariance, double plausibility) {
  const double spread = sigma_xy(covariance);
  const double sigma_theta = std::sqrt(std::max(covariance(2, 2), 0.0));
  if (!localized_) {
    localized_ = spread <= config_.max_sigma_xy && sigma_theta <= config_.max_sigma_theta &&
                 plausibility >= config_.min_plausibility;
    bad_updates_ = 0;
    return localized_;
  }
  const bool bad = spread > config_.lost_sigma_xy || plausibility < config_.lost_plausibility;
  bad_updates_ = bad ? bad_updates_ + 1 : 0;
  if (bad_updates_ >= config_.lost_after) {
    localized_ = false;
    bad_updates_ = 0;
  }
  return localized_;
}

bool moved_enough(const SE2& T_odom_last_update, const SE2& T_odom_robot, double update_distance, double update_angle) {
  const double moved = (T_odom_robot.translation() - T_odom_last_update.translation()).norm();
  const double turned = std::abs(angle_difference(T_odom_robot.theta(), T_odom_last_update.theta()));
  return moved >= update_distance || turned >= update_angle;
}

LocalizationEstimate follow_odometry(const LocalizationEstimate& estimate, const SE2& increment) {
  LocalizationEstimate followed = estimate;
  followed.pose = estimate.pose * increment;
  return followed;
}

}  // namespace slam2d
