// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/hybrid.hpp"

#include <cmath>
#include <optional>

#include "slam2d/core/error.hpp"
#include "slam2d/localization/sensor_model.hpp"

namespace slam2d {

HybridLocalization::HybridLocalization(const LocalizationMap& map, const HybridConfig& config)
    : map_(map), config_(config), grid_(map, config.grid), ekf_(map, config.ekf) {
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
    const bool disagrees = grid.localized && (ekf.pose.translation() - grid.pose.translation()).norm() > config_.max_disagreement &&
                           grid_explains_better(scan, grid.pose, ekf.pose);
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

bool HybridLocalization::grid_explains_better(const LaserScan& scan, const SE2& grid_pose, const SE2& ekf_pose) const {
  const ScanBeams beams = select_beams(scan, config_.ekf.max_beams, config_.ekf.usable_range);
  if (beams.points_robot.empty()) return false;
  const auto fit = [&](const SE2& pose) {
    const std::optional<MatchResult> match = map_.match(beams.points_robot, pose, config_.matcher);
    return map_.plausibility(beams.points_robot, match ? match->T_target_source : pose, config_.grid.status.plausibility_distance);
  };
  const double grid = fit(grid_pose);
  const double ekf = fit(ekf_pose);
  const double n = static_cast<double>(beams.points_robot.size());
  return grid - ekf > config_.takeover_z * std::sqrt((grid * (1.0 - grid) + ekf * (1.0 - ekf)) / n);
}

}  // namespace slam2d
