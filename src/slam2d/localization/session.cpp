// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/session.hpp"

#include <ctime>

#include "slam2d/localization/sensor_model.hpp"

namespace slam2d {

namespace {

constexpr int kStallBeams = 180;  // beams matched within a stall

}  // namespace

LocalizationSession::LocalizationSession(Localizer& localizer, std::optional<Kidnap> kidnap,
                                         const OdometryGuardConfig& odometry_guard, const LocalizationMap* map)
    : localizer_(localizer), kidnap_(kidnap), odometry_guard_(odometry_guard), map_(map) {}

// The motion from the last estimate to the scan matched in the map from there; none for a poor fit.
SE2 LocalizationSession::stall_motion(const LaserScan& scan) const {
  const ScanBeams beams = select_beams(scan, kStallBeams, scan.range_max);
  const std::optional<MatchResult> match = map_->match(beams.points_robot, last_.pose);
  return match && match->converged ? last_.pose.between(match->T_target_source) : SE2();
}

const LocalizationEstimate& LocalizationSession::add(const SE2& T_odom_robot, const LaserScan& scan) {
  const OdometryCheck odometry = odometry_guard_.check(scan.stamp, T_odom_robot);
  if (summary_.scans == 0) {
    first_stamp_ = scan.stamp;
    seen_odom_ = T_odom_robot;
  } else if (odometry.trusted()) {
    seen_odom_ = seen_odom_ * odometry.increment;
  } else if (odometry.fault == OdometryFault::kCatchUp) {
    seen_odom_ = seen_at_moved_ * odometry.increment;
  } else if (odometry.fault == OdometryFault::kStall && map_ != nullptr && last_.localized) {
    seen_odom_ = seen_odom_ * stall_motion(scan);
  }
  const double t = scan.stamp - first_stamp_;
  if (kidnap_ && !summary_.kidnapped_at_s && t >= kidnap_->at) {
    seen_odom_ = seen_odom_ * kidnap_->by;
    seen_at_moved_ = seen_at_moved_ * kidnap_->by;
    summary_.kidnapped_at_s = t;
  }
  if (odometry.moved) seen_at_moved_ = seen_odom_;
  const std::clock_t start = std::clock();
  const bool was_localized = last_.localized;
  last_ = localizer_.update(seen_odom_, scan);
  summary_.localizer_cpu_s += static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  ++summary_.scans;
  summary_.sensor_updates = localizer_.sensor_updates();
  summary_.data_duration_s = t;
  trajectory_.push_back(scan.stamp, last_.pose);
  localized_.push_back(last_.localized);
  if (last_.localized) ++summary_.localized_scans;
  if (last_.localized && !summary_.converged_at_s) summary_.converged_at_s = t;
  if (was_localized && !last_.localized) {
    ++summary_.lost_events;
    const bool counts = kidnap_ ? summary_.kidnapped_at_s.has_value() : true;
    if (counts && !lost_since_ && !summary_.recovered_after_s) {
      lost_since_ = kidnap_ ? *summary_.kidnapped_at_s : t;
    }
  }
  if (last_.localized && lost_since_ && !summary_.recovered_after_s) summary_.recovered_after_s = t - *lost_since_;
  return last_;
}

}  // namespace slam2d
