// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One localization run over a log, the way `slam2d localize` and the tests drive a localizer:
// feeds the scans with their odometry checked by the odometry guard (core/odometry_guard.hpp),
// optionally kidnaps the robot (corrupts the odometry once), times the localizer, and keeps the
// events the summary reports. The odometry the localizer sees:
// - a trusted increment moves it; a jump beyond what the robot could do moves nothing;
// - within a stall, with the map given and the last estimate localized, the scan matched in the
//   map from the last estimate (registration/likelihood_field_match.hpp; at least half of the end points
//   within 0.2 m of an obstacle) moves it by the motion it shows; otherwise nothing does. A
//   localizer predicts from odometry alone: without this it stands still while the robot drives
//   on (MCL with a 15 s stall every 120 s: Intel 0.28 m, FR079 0.73 m; docs/odometry_guard.md);
// - the catch-up at a stall's end carries the whole stall's motion: it is applied from the
//   odometry seen at the scan where the wheel odometry last moved, so the motion matched within
//   the stall is replaced, not counted twice.
//
// - converged_at_s: seconds of data from the first scan to the first step reported localized.
// - lost_events: steps where the state went from localized to not localized.
// - recovered_after_s: with a kidnap, the seconds from the kidnap to the first localized step
//   that follows a lost event after the kidnap (null if the filter never noticed, or never
//   recovered); without one, from the first lost event to the next localized step.
// The kidnap: at the first scan at least kidnap_at seconds after the first scan, the odometry
// the localizer sees gets the extra motion `kidnap_by` (robot frame), and keeps it from then on;
// to the filter the robot has jumped.

#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/odometry_guard.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/localization/localization_map.hpp"
#include "slam2d/localization/localizer.hpp"

namespace slam2d {

struct Kidnap {
  double at = 0.0;  // s after the first scan
  SE2 by;           // extra motion, robot frame
};

struct LocalizationRunSummary {
  std::size_t scans = 0;
  std::size_t sensor_updates = 0;
  double localizer_cpu_s = 0.0;   // CPU time inside Localizer::update
  double data_duration_s = 0.0;   // last scan stamp minus first
  std::optional<double> converged_at_s;
  std::size_t lost_events = 0;
  std::optional<double> kidnapped_at_s;  // when the kidnap was applied (s after the first scan)
  std::optional<double> recovered_after_s;
  std::size_t localized_scans = 0;
};

class LocalizationSession {
 public:
  /// `map` (the localizer's), if given, follows the robot within odometry stalls (above); it must
  /// outlive the session.
  explicit LocalizationSession(Localizer& localizer, std::optional<Kidnap> kidnap = std::nullopt,
                               const OdometryGuardConfig& odometry_guard = {}, const LocalizationMap* map = nullptr);

  /// One scan with the robot's odometry pose at its stamp.
  const LocalizationEstimate& add(const SE2& T_odom_robot, const LaserScan& scan);

  const LocalizationRunSummary& summary() const { return summary_; }
  const OdometryGuardStats& odometry_stats() const { return odometry_guard_.stats(); }
  const Trajectory& trajectory() const { return trajectory_; }
  /// Whether each step was localized, one per trajectory pose.
  const std::vector<bool>& localized() const { return localized_; }

 private:
  SE2 stall_motion(const LaserScan& scan) const;

  Localizer& localizer_;
  std::optional<Kidnap> kidnap_;
  LocalizationRunSummary summary_;
  Trajectory trajectory_;
  std::vector<bool> localized_;
  LocalizationEstimate last_;
  double first_stamp_ = 0.0;
  OdometryGuard odometry_guard_;
  const LocalizationMap* map_;
  SE2 seen_odom_;  // the odometry the localizer sees (guarded, with the kidnap)
  SE2 seen_at_moved_;  // seen_odom_ at the scan where the wheel odometry last moved
  std::optional<double> lost_since_;  // relative time of the lost event that recovery is measured from
};

}  // namespace slam2d
