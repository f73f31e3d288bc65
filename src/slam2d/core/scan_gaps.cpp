// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/scan_gaps.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "slam2d/core/error.hpp"
#include "slam2d/core/motion_fusion.hpp"

namespace slam2d {

void validate(const ScanGapConfig& config) { check_fields(config, "ScanGapConfig"); }

ScanGapDetector::ScanGapDetector(const ScanGapConfig& config) : config_(config) { validate(config_); }

double ScanGapDetector::gap_before(double stamp) {
  const bool first = !started_;
  const double interval = stamp - last_stamp_;
  started_ = true;
  last_stamp_ = stamp;
  if (first) return 0.0;
  if (interval > std::max(config_.seconds, config_.periods * typical_interval_)) {
    ++gaps_;
    return interval;
  }
  constexpr double kIntervalRate = 0.05;  // the running mean's weight of one interval
  if (interval > 0.0) {
    typical_interval_ = typical_interval_ > 0.0 ? typical_interval_ + kIntervalRate * (interval - typical_interval_) : interval;
  }
  return 0.0;
}

bool within_tracker_reach(const ScanGapConfig& config, double window, double window_theta) {
  return window <= config.track_translation && window_theta <= config.track_rotation;
}

void add_to_history(std::vector<OdometryAndEstimate>& history, const OdometryAndEstimate& pair) {
  constexpr double kInterval = 0.5;  // s
  if (history.empty() || pair.stamp - history.back().stamp >= kInterval) history.push_back(pair);
}

Drift odometry_drift_over(std::span<const OdometryAndEstimate> history, double duration) {
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  constexpr double kLeastHistory = 0.25;
  if (history.size() < 2) return {.translation = kUnbounded, .rotation = kUnbounded};
  const double seen = history.back().stamp - history.front().stamp;
  if (seen < kLeastHistory * duration || seen <= 0.0) return {.translation = kUnbounded, .rotation = kUnbounded};
  const double stretch = std::min(duration, seen);
  Drift largest;
  for (std::size_t i = 0, j = 0; i < history.size(); ++i) {
    while (j < history.size() && history[j].stamp - history[i].stamp < stretch) ++j;
    if (j == history.size()) break;
    const Eigen::Vector3d apart = motion_difference(history[i].odometry.between(history[j].odometry),
                                                    history[i].estimate.between(history[j].estimate));
    largest.translation = std::max(largest.translation, apart.head<2>().norm());
    largest.rotation = std::max(largest.rotation, std::abs(apart.z()));
  }
  const double scale = duration / stretch;
  return {.translation = scale * largest.translation, .rotation = scale * largest.rotation};
}

}  // namespace slam2d
