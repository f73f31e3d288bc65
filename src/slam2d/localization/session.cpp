#include "slam2d/localization/session.hpp"

#include <ctime>

namespace slam2d {

LocalizationSession::LocalizationSession(Localizer& localizer, std::optional<Kidnap> kidnap,
                                         const OdometryGuardConfig& odometry_guard)
    : localizer_(localizer), kidnap_(kidnap), odometry_guard_(odometry_guard) {}

const LocalizationEstimate& LocalizationSession::add(const SE2& T_odom_robot, const LaserScan& scan) {
  const OdometryCheck odometry = odometry_guard_.check(scan.stamp, T_odom_robot);
  if (summary_.scans == 0) {
    first_stamp_ = scan.stamp;
    seen_odom_ = T_odom_robot;
  } else if (odometry.trusted() || odometry.fault == OdometryFault::kCatchUp) {
    // A localizer predicts from odometry alone: during a stall nothing moved it, so the catch-up is
    // motion not yet counted, and is kept. A jump beyond what the robot could do moves nothing.
    seen_odom_ = seen_odom_ * odometry.increment;
  }
  const double t = scan.stamp - first_stamp_;
  if (kidnap_ && !summary_.kidnapped_at_s && t >= kidnap_->at) {
    seen_odom_ = seen_odom_ * kidnap_->by;
    summary_.kidnapped_at_s = t;
  }
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
