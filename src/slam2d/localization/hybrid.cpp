// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/hybrid.hpp"

#include "slam2d/core/error.hpp"

namespace slam2d {

HybridLocalization::HybridLocalization(const LocalizationMap& map, const HybridConfig& config)
    : config_(config), grid_(map, config.grid), ekf_(map, config.ekf) {
  check_fields(config_, "HybridConfig");
}

void HybridLocalization::initialize(const SE2& T_map_robot, const Covariance3& covariance) {
  grid_.initialize(T_map_robot, covariance);
  ekf_.initialize(T_map_robot, covariance);
  ekf_active_ = true;
}

void HybridLocalization::initialize_global() {
  grid_.initialize_global();
  ekf_active_ = false;
}

LocalizationEstimate HybridLocalization::update(const SE2& T_odom_robot, const LaserScan& scan) {
  const std::size_t before = grid_.sensor_updates() + ekf_.sensor_updates();
  const LocalizationEstimate grid = grid_.update(T_odom_robot, scan);
  LocalizationEstimate result = grid;
  if (ekf_active_) {
    const LocalizationEstimate ekf = ekf_.update(T_odom_robot, scan);
    const bool disagrees =
        grid.localized && (ekf.pose.translation() - grid.pose.translation()).norm() > config_.max_disagreement;
    const bool lost = ekf_.lost();
    if (disagrees || lost) {
      ekf_active_ = false;
    } else {
      result = ekf;
    }
  }
  if (!ekf_active_ && grid.localized) {
    // The grid is unique again: restart the EKF from it.
    ekf_.initialize(grid.pose, grid.covariance);
    result = ekf_.update(T_odom_robot, scan);
    ekf_active_ = true;
    ++handovers_;
  }
  if (grid_.sensor_updates() + ekf_.sensor_updates() > before) ++sensor_updates_;
  return result;
}

}  // namespace slam2d
