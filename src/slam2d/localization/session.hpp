#pragma once
// One localization run over a log, the way `slam2d localize` and the tests drive a localizer:
// feeds the scans with their odometry checked by the odometry guard (core/odometry_guard.hpp: a
// jump moves nothing; a stall's catch-up is kept, since the localizer's prediction did not follow
// the robot during the stall), optionally kidnaps the robot (corrupts the odometry once),
// times the localizer, and keeps the events the summary reports.
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
  explicit LocalizationSession(Localizer& localizer, std::optional<Kidnap> kidnap = std::nullopt,
                               const OdometryGuardConfig& odometry_guard = {});

  /// One scan with the robot's odometry pose at its stamp.
  const LocalizationEstimate& add(const SE2& T_odom_robot, const LaserScan& scan);

  const LocalizationRunSummary& summary() const { return summary_; }
  const OdometryGuardStats& odometry_stats() const { return odometry_guard_.stats(); }
  const Trajectory& trajectory() const { return trajectory_; }
  /// Whether each step was localized, one per trajectory pose.
  const std::vector<bool>& localized() const { return localized_; }

 private:
  Localizer& localizer_;
  std::optional<Kidnap> kidnap_;
  LocalizationRunSummary summary_;
  Trajectory trajectory_;
  std::vector<bool> localized_;
  LocalizationEstimate last_;
  double first_stamp_ = 0.0;
  OdometryGuard odometry_guard_;
  SE2 seen_odom_;  // the odometry the localizer sees (guarded, with the kidnap)
  std::optional<double> lost_since_;  // relative time of the lost event that recovery is measured from
};

}  // namespace slam2d
