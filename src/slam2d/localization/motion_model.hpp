// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The odometry motion model: S. Thrun, W. Burgard, D. Fox, "Probabilistic Robotics", 2005,
// Sec. 5.4. The motion between two odometry readings is split into a rotation, a translation and
// a second rotation (Eq. 5.34 .. 5.36, `decompose_odometry`); each part is perturbed by zero-mean
// Gaussian noise whose variance grows with the motion, with the four parameters alpha1..alpha4:
//   var(rot1)  = alpha1 rot1^2 + alpha2 trans^2
//   var(trans) = alpha3 trans^2 + alpha4 (rot1^2 + rot2^2)
//   var(rot2)  = alpha1 rot2^2 + alpha2 trans^2
// `sample_odometry_motion` is Table 5.6 (sample_motion_model_odometry), for particle filters;
// `predict_odometry_motion` is the EKF's prediction (Table 7.3 in the odometry form): the pose
// g(x, u) and its covariance G P G^T + V M V^T with G = dg/dx, V = dg/du.
//
// Two practical details (as AMCL does): a translation shorter than 1 cm has no rot1 (turning on
// the spot), and a robot driving backwards has rot1 near +-pi: the noise then scales with the
// angle to the backward direction, not with the half turn. A small floor on each variance keeps
// the covariance of a standing robot invertible.

#include <Eigen/Core>
#include <optional>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct OdometryMotionConfig {
  double alpha1 = 0.05;
  double alpha2 = 0.01;
  double alpha3 = 0.05;
  double alpha4 = 0.01;
  double min_rotation_sigma = 1e-3;
  double min_translation_sigma = 1e-3;
};

template <typename Fields>
void describe(Fields& f, OdometryMotionConfig& c) {
  f.number("alpha1", c.alpha1, "rad^2/rad^2", at_least(0), "rotation noise from rotation");
  f.number("alpha2", c.alpha2, "rad^2/m^2", at_least(0), "rotation noise from translation");
  f.number("alpha3", c.alpha3, "m^2/m^2", at_least(0), "translation noise from translation");
  f.number("alpha4", c.alpha4, "m^2/rad^2", at_least(0), "translation noise from rotation");
  f.number("min_rotation_sigma", c.min_rotation_sigma, "rad", at_least(0), "floor of the rotation standard deviations");
  f.number("min_translation_sigma", c.min_translation_sigma, "m", at_least(0),
           "floor of the translation standard deviation");
}

/// Throws Error unless every field is finite and non-negative.
void validate(const OdometryMotionConfig& config);

/// The control u = (rot1, trans, rot2) between two odometry poses (Eq. 5.34 .. 5.36).
struct OdometryControl {
  double rot1 = 0.0;   // rad
  double trans = 0.0;  // m
  double rot2 = 0.0;   // rad
  Eigen::Vector3d vector() const { return {rot1, trans, rot2}; }
};
OdometryControl decompose_odometry(const SE2& T_odom_previous, const SE2& T_odom_current);

/// The noise-free motion g(x, u): the pose after applying u at `pose`. J_pose = dg/dx,
/// J_control = dg/du (u as (rot1, trans, rot2)).
SE2 apply_odometry(const SE2& pose, const OdometryControl& u, Matrix3* J_pose = nullptr, Matrix3* J_control = nullptr);

/// M: the diagonal covariance of (rot1, trans, rot2) for a control, with the floors.
Eigen::Matrix3d control_covariance(const OdometryControl& u, const OdometryMotionConfig& config);

/// Table 5.6: a sample of the pose after the control.
SE2 sample_odometry_motion(const SE2& pose, const OdometryControl& u, const OdometryMotionConfig& config, Rng& rng);
/// The same with the standard deviations of (rot1, trans, rot2) given (sqrt of the diagonal of
/// control_covariance), for a particle set moved by one control.
SE2 sample_odometry_motion(const SE2& pose, const OdometryControl& u, const Eigen::Vector3d& sigmas, Rng& rng);

/// The EKF prediction: g(x, u) and G P G^T + V M V^T.
struct MotionPrediction {
  SE2 pose;
  Covariance3 covariance;
};
MotionPrediction predict_odometry_motion(const SE2& pose, const Covariance3& covariance, const OdometryControl& u,
                                         const OdometryMotionConfig& config);

/// The motion noise learnt online (issue 40, docs/fusion_by_uncertainty.md, "The localizers"):
/// over each stretch between two pose measurements (scan matches against the map) that is at least
/// span_distance long or turns at least span_angle, the odometry's increment against the measured
/// one. Translation and rotation each get a scale (NoiseScaleEstimate, core/motion_fusion.hpp)
/// that multiplies the model's standard deviations: alpha3, alpha4 and the translation floor for
/// the translation, alpha1, alpha2 and the rotation floor for the rotation. The translation's
/// residual carries the rotation noise's share too (a heading error moves the robot sideways):
/// the stretch's covariance is propagated in the two shares, and the rotation's, at its current
/// scale, counts as known when the translation's scale is learnt. A stretch rather than a step,
/// because over one step a map match's noise hides the odometry's; over half a metre the
/// odometry's grows above it.
/// The same stretches can teach the odometry's systematic error (OdometryCalibration,
/// core/motion_fusion.hpp: its scales of distance and turn and its heading drift per metre): each
/// increment is then corrected for it before it predicts, and the noise scales learn what is left.
/// An option, off: it finds the error (Intel's drift, injected faults), but MCL on FR079 under
/// several laser and odometry faults lost accuracy with it (docs/fusion_by_uncertainty.md).
struct MotionNoiseLearningConfig {
  double window = 100.0;  // stretches the scales average over; 0: the fixed model
  double min_scale = 0.5;
  double max_scale = 10.0;
  double span_distance = kOdometryStretchSpan;  // m
  double span_angle = kOdometryStretchSpan;     // rad
  OdometryCalibrationConfig calibration{.window = 0.0};  // off (docs/fusion_by_uncertainty.md)
};

template <typename Fields>
void describe(Fields& f, MotionNoiseLearningConfig& c) {
  f.number("window", c.window, "1", at_least(0), "stretches the learnt scales average over (0: the fixed model)");
  f.number("min_scale", c.min_scale, "1", open_closed(0, 1), "lower bound of a learnt scale of the standard deviations");
  f.number("max_scale", c.max_scale, "1", at_least(1), "upper bound");
  f.number("span_distance", c.span_distance, "m", greater_than(0), "a stretch ends after this much travel ...");
  f.number("span_angle", c.span_angle, "rad", greater_than(0), "... or this much turn");
  f.section("calibration", c.calibration, "the odometry's systematic error learnt from the same stretches (core/motion_fusion.hpp)");
}

/// Learns the scales of an odometry motion model from pose measurements (header above).
class MotionNoiseLearner {
 public:
  MotionNoiseLearner(const OdometryMotionConfig& model, const MotionNoiseLearningConfig& config);

  /// The model with its standard deviations scaled by what has been learnt.
  OdometryMotionConfig model() const;

  /// The odometry's increment (T_previous_current) corrected for its systematic error learnt so far.
  SE2 corrected(const SE2& increment) const;
  /// One odometry increment since the last call, as the odometry measured it: extends the current
  /// stretch and returns the control that predicts it (the corrected increment decomposed,
  /// decompose_odometry).
  OdometryControl move(const SE2& increment);
  /// A pose measured against the map (its covariance in the map frame): ends the stretch when it
  /// is long enough, learns from it and starts the next one here. One of unknown covariance
  /// (kUnknownVariance) ends the stretch unlearnt.
  void measured(const SE2& pose, const Covariance3& covariance);
  /// The scan matched against the map at a localized estimate (LocalizationMap::match), or none
  /// (the estimate is not one localized place, or the match failed): none starts the stretch again.
  void measured(const std::optional<MatchResult>& match);
  /// Forgets the current stretch (the next measurement starts one): after a relocalization.
  void restart() { anchored_ = false; }
  /// Whether measured() would use a measurement now (learning on, and no stretch or a long one).
  bool wants_measurement() const {
    const bool learning = config_.window > 0.0 || config_.calibration.window > 0.0;
    return learning && (!anchored_ || travelled_ >= config_.span_distance || turned_ >= config_.span_angle);
  }

  double translation_scale() const { return translation_.scale(); }
  double rotation_scale() const { return rotation_.scale(); }
  std::size_t stretches() const { return translation_.observations(); }
  const OdometryCalibration& calibration() const { return calibration_; }

 private:
  void start(const SE2& pose, const Covariance3& covariance);
  void learn_odometry_noise(const Eigen::Vector3d& e, const Covariance3& measured);
  void learn_calibration(const SE2& increment, const Covariance3& measured);

  OdometryMotionConfig model_;
  OdometryMotionConfig translation_noise_;  // the model's translation noise alone
  OdometryMotionConfig rotation_noise_;     // its rotation noise alone
  MotionNoiseLearningConfig config_;
  NoiseScaleEstimate translation_;
  NoiseScaleEstimate rotation_;
  OdometryCalibration calibration_;
  bool anchored_ = false;
  SE2 anchor_;                     // the measured pose the stretch starts at
  Covariance3 anchor_covariance_;  // its covariance (map frame)
  SE2 stretch_;                    // the odometry's increment since the anchor, corrected
  OdometryStretch raw_;            // ... as the odometry measured it
  Covariance3 from_translation_;   // its covariance under the unscaled model's translation noise
  Covariance3 from_rotation_;      // ... and rotation noise
  double travelled_ = 0.0;
  double turned_ = 0.0;
};

}  // namespace slam2d
