// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// EKF localization with scan-matching updates: J.-S. Gutmann, W. Burgard, D. Fox, K. Konolige,
// "An experimental comparison of localization methods", IROS 1998 (the scan-matching Kalman
// filter of that comparison), with the odometry motion model of S. Thrun et al., "Probabilistic
// Robotics", 2005 (Table 7.3 in its odometry form, motion_model.hpp).
//
// Each scan: predict the pose and covariance with the odometry since the last scan (G P G^T +
// V M V^T), match the scan against the map around the predicted pose to get a pose measurement
// z with covariance R, and fuse it in information form (the measurement is the pose itself,
// H = I):
//   P+^-1 = P^-1 + R^-1,   x+ = x + P+ R^-1 (z - x).
// The match has two stages. Correlative matching (E. Olson, ICRA 2009; registration/
// correlative.hpp, branch-and-bound) against a lookup table of the map's occupied cells, built
// once, searches a window of +-3 sigma of the predicted covariance (clamped to the window_*
// bounds): it finds the best pose in the window rather than the nearest local minimum, and its
// response distribution over the window is R, so a corridor's long axis or a second similar
// place inside the window shows in R. The table's steps (a map cell, half a degree) are then
// refined by least squares on the distance field (registration/likelihood_field_match.hpp), whose fit feeds the inlier
// gate.
// Gates reject implausible matches (no fusion; the covariance grows by rejection_sigma per
// rejected scan, so that after a wheel slip the gate opens to the next consistent match):
//   - fewer than min_inlier_fraction of the end points lie within the matcher's inlier_distance
//     of an obstacle after the match (a match that used up its iterations still counts: near the
//     optimum the damped steps only get smaller);
//   - the innovation's Mahalanobis distance (z - x)^T (P + R)^-1 (z - x) exceeds gate_chi2
//     (chi-square, 3 degrees of freedom).
// After lost_after_rejections consecutive rejections the filter reports itself lost instead of
// pretending to track, and stays lost (it only predicts) until initialize() is called again: an
// EKF cannot relocalize globally (use mcl, markov or hybrid for that).

#include <cstddef>
#include <numbers>
#include <string>

#include "slam2d/core/covariance.hpp"
#include "slam2d/localization/localization_map.hpp"
#include "slam2d/localization/localizer.hpp"
#include "slam2d/localization/motion_model.hpp"
#include "slam2d/registration/likelihood_field_match.hpp"
#include "slam2d/registration/correlative_grid.hpp"

namespace slam2d {

struct EkfConfig {
  // Rotation noise from rotation well above the particle filter's: a Gaussian cannot absorb the
  // wheel slip of a fast turn in the tails as a particle set does, and a rejected match costs more.
  OdometryMotionConfig motion{.alpha1 = 0.2};
  LikelihoodFieldMatchConfig matcher{};
  // The correlative stage: window half-widths +-3 sigma of the prediction, clamped to these.
  double min_window_xy = 0.1;
  double max_window_xy = 0.5;  // >= min_window_xy
  double min_window_theta = 0.05;
  double max_window_theta = 0.35;  // >= min_window_theta
  double angular_step = 0.0087;  // half a degree
  double table_sigma = 0.05;     // one map cell of 5 cm
  int max_beams = 90;
  double usable_range = 30.0;
  double min_inlier_fraction = 0.5;
  double gate_chi2 = 16.27;  // chi-square(3) at 0.999
  int lost_after_rejections = 10;
  // Each rejected scan widens the covariance by this much (the odometry may have slipped: the
  // gate must open to the first consistent match rather than reject it forever).
  double rejection_sigma_xy = 0.05;
  double rejection_sigma_theta = 0.02;
  // Added to the matcher's covariance: consecutive scans of a standing robot are not independent
  // measurements, and the Hessian covariance of ~90 correlated end points is optimistic.
  double measurement_sigma_xy = 0.1;
  double measurement_sigma_theta = 0.05;
  // The odometry's noise learnt from the accepted matches (MotionNoiseLearner, motion_model.hpp).
  MotionNoiseLearningConfig motion_noise{};
  LocalizationStatusConfig status{};
};

template <typename Fields>
void describe(Fields& f, EkfConfig& c) {
  f.section("motion", c.motion, "the prediction's odometry noise");
  f.section("matcher", c.matcher, "the refinement");
  f.number("min_window_xy", c.min_window_xy, "m", greater_than(0), "smallest translation half-width of the correlative stage");
  f.number("max_window_xy", c.max_window_xy, "m", greater_than(0), "largest one (>= min_window_xy)");
  f.number("min_window_theta", c.min_window_theta, "rad", greater_than(0), "smallest rotation half-width");
  f.number("max_window_theta", c.max_window_theta, "rad", open_closed(0, std::numbers::pi),
           "largest one (>= min_window_theta)");
  f.number("angular_step", c.angular_step, "rad", greater_than(0), "rotation step of the correlative stage");
  f.number("table_sigma", c.table_sigma, "m", greater_than(0), "the lookup table's kernel");
  f.number("max_beams", c.max_beams, "1", at_least(1), "end points matched per scan");
  f.number("usable_range", c.usable_range, "m", greater_than(0), "longer readings are not matched");
  f.number("min_inlier_fraction", c.min_inlier_fraction, "1", between(0, 1), "fewer inliers and the match is rejected");
  f.number("gate_chi2", c.gate_chi2, "1", greater_than(0), "Mahalanobis gate on the innovation");
  f.number("lost_after_rejections", c.lost_after_rejections, "scans", at_least(1), "rejections in a row before lost");
  f.number("rejection_sigma_xy", c.rejection_sigma_xy, "m", any_value(), "covariance widening per rejected scan");
  f.number("rejection_sigma_theta", c.rejection_sigma_theta, "rad", any_value(), "... in heading");
  f.number("measurement_sigma_xy", c.measurement_sigma_xy, "m", any_value(), "added to the matcher's covariance");
  f.number("measurement_sigma_theta", c.measurement_sigma_theta, "rad", any_value(), "... in heading");
  f.section("motion_noise", c.motion_noise, "the motion noise's scales learnt from the accepted matches");
  f.section("status", c.status, "when the estimate counts as localized or lost");
}

/// Throws Error for values outside the ranges above.
void validate(const EkfConfig& config);

struct EkfStats {
  std::size_t updates = 0;          // scans matched
  std::size_t accepted = 0;         // fused
  std::size_t rejected_match = 0;   // too few inliers
  std::size_t rejected_gate = 0;    // Mahalanobis gate
};

class EkfLocalization : public Localizer {
 public:
  /// The map must outlive the filter. Call initialize() before update().
  EkfLocalization(const LocalizationMap& map, const EkfConfig& config = {});

  /// The prior: pose and covariance. The next update() takes its odometry as the reference.
  void initialize(const SE2& T_map_robot, const Covariance3& covariance);
  bool initialized() const { return initialized_; }

  LocalizationEstimate update(const SE2& T_odom_robot, const LaserScan& scan) override;
  std::size_t sensor_updates() const override { return stats_.updates; }
  std::string name() const override { return "ekf"; }

  const EkfStats& stats() const { return stats_; }
  /// lost_after_rejections consecutive matches have failed the gates.
  bool lost() const { return rejections_ >= config_.lost_after_rejections; }
  const SE2& pose() const { return pose_; }
  const Covariance3& covariance() const { return covariance_; }
  const MotionNoiseLearner* motion_noise() const override { return &motion_noise_; }

 private:
  /// Matches and fuses; returns true when the measurement passed the gates.
  bool correct(const std::vector<Eigen::Vector2d>& points_robot);

  const LocalizationMap& map_;
  EkfConfig config_;
  CorrelativeGrid table_;  // the map's occupied cells, for the correlative stage
  bool initialized_ = false;
  bool started_ = false;
  SE2 last_odom_;
  SE2 pose_;
  Covariance3 covariance_ = Covariance3::Identity();
  LocalizationStatus status_;
  MotionNoiseLearner motion_noise_;
  int rejections_ = 0;
  EkfStats stats_;
};

}  // namespace slam2d
