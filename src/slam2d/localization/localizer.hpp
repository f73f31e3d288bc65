// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What every localization method reports, and the common interface the CLI drives.
//
// Each step a localizer receives the robot's odometry pose (T_odom_robot, any frame: only the
// motion between steps is used) and the scan taken there, and returns its estimate of
// T_map_robot, a covariance, and whether it considers itself localized. "Localized" is decided
// the same way for every method (LocalizationStatus): the estimate is unique (its covariance small)
// and plausible (most scan end points fall near obstacles of the map at the estimate), with
// hysteresis so that one bad scan does not count as a lost event.

#include <cstddef>
#include <string>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

class MotionNoiseLearner;  // motion_model.hpp

struct LocalizationEstimate {
  SE2 pose;                                          // T_map_robot
  Covariance3 covariance = Covariance3::Identity();  // m^2, m rad, rad^2
  bool localized = false;
  double plausibility = 0.0;  // 1, fraction of end points near an obstacle at the estimate (last sensor update)
};

struct LocalizationStatusConfig {
  double plausibility_distance = 0.15;
  // Becoming localized: all three hold.
  double max_sigma_xy = 0.5;
  double max_sigma_theta = 0.3;
  double min_plausibility = 0.7;
  // Becoming lost: one of these for `lost_after` consecutive sensor updates.
  double lost_sigma_xy = 1.0;
  double lost_plausibility = 0.5;
  int lost_after = 3;
};

template <typename Fields>
void describe(Fields& f, LocalizationStatusConfig& c) {
  f.number("plausibility_distance", c.plausibility_distance, "m", greater_than(0),
           "an end point this close to an obstacle is explained");
  f.number("max_sigma_xy", c.max_sigma_xy, "m", any_value(),
           "localized below this sqrt of the largest eigenvalue of the (x, y) block ...");
  f.number("max_sigma_theta", c.max_sigma_theta, "rad", any_value(), "... and this heading sigma ...");
  f.number("min_plausibility", c.min_plausibility, "1", any_value(), "... and from this plausibility");
  f.number("lost_sigma_xy", c.lost_sigma_xy, "m", any_value(), "lost above this (x, y) sigma ...");
  f.number("lost_plausibility", c.lost_plausibility, "1", any_value(), "... or below this plausibility ...");
  f.number("lost_after", c.lost_after, "sensor updates", at_least(1), "... for this many updates in a row");
}

/// The localized / lost state machine.
class LocalizationStatus {
 public:
  explicit LocalizationStatus(const LocalizationStatusConfig& config = {}) : config_(config) {}
  /// After a sensor update: returns the new state.
  bool update(const Covariance3& covariance, double plausibility);
  bool localized() const { return localized_; }
  void reset() {
    localized_ = false;
    bad_updates_ = 0;
  }
  const LocalizationStatusConfig& config() const { return config_; }

 private:
  LocalizationStatusConfig config_;
  bool localized_ = false;
  int bad_updates_ = 0;
};

/// sqrt of the largest eigenvalue of the translational block (m).
double sigma_xy(const Covariance3& covariance);

/// The filters' update rule: a sensor update once the odometry moved update_distance (m) or turned
/// update_angle (rad) since the last one.
bool moved_enough(const SE2& T_odom_last_update, const SE2& T_odom_robot, double update_distance, double update_angle);
/// Between sensor updates: the last estimate carried along the odometry's increment since then
/// (T_last_update_robot).
LocalizationEstimate follow_odometry(const LocalizationEstimate& estimate, const SE2& increment);

class Localizer {
 public:
  virtual ~Localizer() = default;
  /// One step: the odometry pose at the scan and the scan.
  virtual LocalizationEstimate update(const SE2& T_odom_robot, const LaserScan& scan) = 0;
  /// Sensor updates done so far (filters skip them while the robot stands still).
  virtual std::size_t sensor_updates() const = 0;
  virtual std::string name() const = 0;
  /// The odometry's motion noise the localizer learnt (motion_model.hpp), if it learns one.
  virtual const MotionNoiseLearner* motion_noise() const { return nullptr; }
};

}  // namespace slam2d
