// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One motion measured twice: the wheel odometry's increment and a scan match, each with its own
// covariance, fused by their information (the product of two Gaussians), after a consistency test.
//
// - The odometry's covariance comes from a motion noise model of distance and turn (the form of
//   Thrun, Burgard and Fox, "Probabilistic Robotics", Sec. 5.4, with standard deviations growing
//   linearly rather than variances): an increment of length d that turns by a has
//     sigma_translation = rest_translation + translation_per_metre d + translation_per_radian |a|,
//     sigma_rotation    = rest_rotation + rotation_per_metre d + rotation_per_radian |a|,
//   each times a scale the model estimates online from how well the odometry agrees with matches
//   it is fused with: the mean of (residual^2 - the match's variance) / the model's variance over
//   the last `window` agreements, each sample clipped at the gate (so one wrong match cannot blow
//   the model up) and the scale kept within [min_scale, max_scale].
// - The match's covariance is the matcher's own (Censi 2007 or the Gauss-Newton Hessian), floored
//   (no matcher is better than its map's cell or its sensor) and inflated along its weak direction
//   when it is degenerate (a corridor's axis): see registration/match_fusion.hpp.
// - Consistency (Mahalanobis): the squared distance of the two under the sum of their covariances
//   against a chi-square gate (3 degrees of freedom). Within it, the information-weighted mean.
//   Beyond it they disagree, and the better-conditioned one along the disagreement wins alone: the
//   one whose variance along the difference is smaller (the larger Mahalanobis distance of the
//   difference under its own covariance). The caller counts the disagreements and their winners.
//
// Increments are small (scan to scan, keyframe to scan): they are fused in their coordinates
// (x, y, theta), the heading's difference wrapped.

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OdometryNoiseConfig {
  double rest_translation = 0.005;       // m
  double rest_rotation = 0.005;          // rad
  double translation_per_metre = 0.05;   // m per m travelled
  double translation_per_radian = 0.02;  // m per rad turned
  double rotation_per_metre = 0.05;      // rad per m travelled
  double rotation_per_radian = 0.05;     // rad per rad turned
  double window = 100.0;                 // agreements the online scale averages over (0: a fixed model)
  double min_scale = 0.2;                // 1, the scale's bounds
  double max_scale = 20.0;
};

template <typename Fields>
void describe(Fields& f, OdometryNoiseConfig& c) {
  f.number("rest_translation", c.rest_translation, "m", greater_than(0), "translation sigma of an increment that did not move");
  f.number("rest_rotation", c.rest_rotation, "rad", greater_than(0), "rotation sigma of an increment that did not move");
  f.number("translation_per_metre", c.translation_per_metre, "m per m", at_least(0), "growth of the translation sigma with distance");
  f.number("translation_per_radian", c.translation_per_radian, "m per rad", at_least(0), "... with the angle turned");
  f.number("rotation_per_metre", c.rotation_per_metre, "rad per m", at_least(0), "growth of the rotation sigma with distance");
  f.number("rotation_per_radian", c.rotation_per_radian, "rad per rad", at_least(0), "... with the angle turned");
  f.number("window", c.window, "1", at_least(0), "agreements the online scale of the sigmas averages over (0: fixed)");
  f.number("min_scale", c.min_scale, "1", greater_than(0), "lower bound of the online scale (<= 1)");
  f.number("max_scale", c.max_scale, "1", at_least(1), "upper bound of the online scale");
}

/// Throws Error for out-of-range values.
void validate(const OdometryNoiseConfig& config);

/// A noise model's scale learnt online by covariance matching: the mean, over the last `window`
/// samples, of (residual^2 per degree of freedom - the variance the residual carries besides the
/// model's) / the model's variance, each residual clipped at the chi-square gate of the current
/// total (so one wrong sample cannot blow the model up), the squared scale kept within
/// [min_scale^2, max_scale^2]. It starts at 1; window 0 keeps it there.
class NoiseScaleEstimate {
 public:
  NoiseScaleEstimate(double window, double min_scale, double max_scale);

  void observe(double residual2_per_dof, double model_variance, double other_variance);

  double scale() const { return scale_; }
  std::size_t observations() const { return observations_; }

 private:
  double window_;
  double min_scale_;
  double max_scale_;
  double scale_ = 1.0;
  std::size_t observations_ = 0;
};

/// The odometry's systematic error learnt online. A wheel odometry is wrong in the same way from
/// one metre to the next (J. Borenstein, L. Feng, "Measurement and correction of systematic
/// odometry errors in mobile robots", IEEE T-RA 1996: unequal wheel diameters turn the robot in
/// proportion to the distance driven, a wrong wheelbase scales its turns, a wrong wheel diameter its
/// distance). Noise does not average that out, and a filter that weighs the odometry as if it were
/// only noisy lags behind it (the Intel log's odometry turns 0.057 rad per metre it drives: the
/// EKF's heading ran 0.009 rad behind the map's on average). Over stretches measured at both ends
/// (scan matches against a map), the rotation residual (measured minus odometry) is regressed on
/// the measured turn and length, and the residual of the odometry's displacement along the
/// measured one on the measured length, by weighted recursive least squares forgetting over
/// `window` stretches (every regressor the measured motion, never the odometry's, whose noise
/// would bias the estimates: errors in variables), with a ridge prior of
/// prior_sigma at zero (an online self-calibration in the spirit of N. Roy and S. Thrun, "Online
/// self-calibration for mobile robots", ICRA 1999, in linear form). A stretch whose residual lies
/// beyond 3 sigma of the current fit weighs (3 sigma / residual)^2 as much (a slip, a wrong match).
/// Corrected: distance times translation_scale, turn times rotation_scale plus
/// drift_per_metre times the distance; nothing while the fit lies beyond max_correction on any of
/// the three (credible()), which no wheel odometry's systematic error reaches. Each of the three is
/// corrected only by what of it stands out of its own uncertainty: the fit's standard error (from
/// the normal equations, scaled up by the residuals' chi^2 per stretch where that is above 1), the
/// estimate shrunk by the non-negative garrote at `significance` of it (none within it, nearly all
/// far beyond it). With it, an odometry with no systematic error to speak of has none corrected,
/// whatever small error the matches' own errors suggest.
struct OdometryCalibrationConfig {
  double window = 100.0;        // stretches the estimate forgets over; 0: no correction
  double prior_sigma = 0.05;    // 1 and rad/m, the ridge prior of each parameter at zero
  double max_correction = 0.2;  // 1 and rad/m, the largest scale error and drift believed (beyond: none corrected)
  double min_distance = 0.2;    // m, shorter displacements teach no translation scale
  double significance = 0.0;    // standard errors each estimate must stand out by (0: the fit as it is)
};

template <typename Fields>
void describe(Fields& f, OdometryCalibrationConfig& c) {
  f.number("window", c.window, "1", at_least(0), "stretches the odometry's systematic error is estimated over (0: not corrected)");
  f.number("prior_sigma", c.prior_sigma, "1", greater_than(0), "prior standard deviation of each error (scales, and drift in rad/m) at zero");
  f.number("max_correction", c.max_correction, "1", between(0, 0.5),
           "largest scale error, and drift in rad/m, believed; a fit beyond it on any of the three corrects nothing");
  f.number("min_distance", c.min_distance, "m", greater_than(0), "stretches that move less teach no translation scale");
  f.number("significance", c.significance, "1", at_least(0),
           "standard errors of its fit each error must exceed to be corrected; beyond, shrunk by the garrote (0: the fit as it is)");
}

class OdometryCalibration {
 public:
  explicit OdometryCalibration(const OdometryCalibrationConfig& config = {});

  /// One stretch: the odometry's signed turn (rad), signed path length (m, backwards negative) and
  /// displacement (m, in its start frame) against the measured rotation and displacement (the
  /// same frame), with the residuals' variances besides the systematic error (the measurements'
  /// and the odometry's noise).
  void observe(double turn, double path, const Eigen::Vector2d& displacement, double measured_rotation,
               const Eigen::Vector2d& measured_displacement, double rotation_variance, double translation_variance);

  // What is corrected: the fit, each error shrunk at `significance` (the fit itself with 0).
  double translation_scale() const;  // true distance / the odometry's
  double rotation_scale() const;     // true turn / the odometry's, less the drift
  double drift_per_metre() const;    // rad per metre of the odometry's (signed) path
  std::size_t observations() const { return observations_; }

  /// The fit lies within max_correction on all three (the accessors above clamp to it).
  bool credible() const;
  /// The odometry's increment (T_previous_current) corrected for the error learnt so far; as it
  /// is while the fit is not credible().
  SE2 corrected(const SE2& increment) const;

 private:
  OdometryCalibrationConfig config_;
  // Forgetting normal equations: rotation on (measured turn, measured length), translation on
  // the measured length.
  Eigen::Matrix2d rotation_information_ = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rotation_vector_ = Eigen::Vector2d::Zero();
  double translation_information_ = 0.0;
  double translation_vector_ = 0.0;
  Eigen::Vector2d rotation_ = Eigen::Vector2d::Zero();  // the fit (a, b), in observe()
  double translation_ = 0.0;                            // c
  // The residuals' weighted squares and count, forgetting alike: chi^2 per stretch, by which the
  // fit's variance from its information is scaled up where the given variances understate the
  // scatter.
  struct Scatter {
    double chi2 = 0.0, count = 0.0;
    void add(double keep, double weighted_square) {
      chi2 = keep * chi2 + weighted_square;
      count = keep * count + 1.0;
    }
    double variance(double inverse_information) const {
      return inverse_information * std::max(1.0, count > 0.0 ? chi2 / count : 1.0);
    }
  };
  Scatter rotation_scatter_, translation_scatter_;
  Eigen::Vector2d applied_rotation_ = Eigen::Vector2d::Zero();  // (a, b) shrunk at significance
  double applied_translation_ = 0.0;                            // c, the same
  std::size_t observations_ = 0;
};

/// A stretch of the odometry compared with the measured motion ends after this much travel (m) or
/// turn (rad): long enough for the matches' errors to be small against the odometry's systematic
/// error, short enough to follow it (the localizers' span, the RBPF's calibration stretch).
inline constexpr double kOdometryStretchSpan = 0.5;

/// The odometry's increments since a measured pose, as the odometry measured them: what a stretch
/// of OdometryCalibration compares with the measured motion.
struct OdometryStretch {
  SE2 displacement;   // the increments composed
  double turn = 0.0;  // their signed turn, rad
  double path = 0.0;  // their signed path length, m (backwards negative)

  void add(const SE2& increment);
};

/// A tracker's stretches of OdometryCalibration: from the measured pose at a matched scan to the
/// first later one kOdometryStretchSpan of measured travel or turn away (the measured motion, not
/// the odometry's: ended on the odometry's, the jitter of an odometry would select the stretches),
/// every increment between them trusted by the guard and matched. The measured motion's uncertainty is the two matches' and the odometry
/// noise of the increments between them. A scan that is not usable (its increment not trusted,
/// no match) ends the stretch unlearnt.
class CalibrationStretches {
 public:
  /// One scan: the odometry's raw increment from the previous scan and the noise the model gives
  /// it, the scan's measured pose and that match's covariance.
  void add(bool usable, const SE2& increment, const Covariance3& increment_noise, const SE2& measured,
           const Covariance3& measured_covariance, OdometryCalibration& calibration);

 private:
  bool anchored_ = false;
  SE2 anchor_;                                              // measured pose the stretch starts at
  Covariance3 anchor_covariance_ = Covariance3::Zero();     // that match's covariance
  OdometryStretch raw_;                                     // the odometry's increments since
  Covariance3 odometry_covariance_ = Covariance3::Zero();   // their noise, summed
};

/// The odometry's motion noise with its online scales (translation and rotation).
class OdometryNoiseModel {
 public:
  explicit OdometryNoiseModel(const OdometryNoiseConfig& config = {});

  /// The covariance of the odometry increment (diagonal in the increment's start frame).
  Covariance3 covariance(const SE2& increment) const;

  /// Learns from one agreement: the odometry's increment against the same motion measured by a
  /// scan match (with its covariance). Call it only with matches the caller accepted.
  void observe(const SE2& increment, const SE2& measured, const Covariance3& measured_covariance);

  double translation_scale() const { return translation_scale_.scale(); }
  double rotation_scale() const { return rotation_scale_.scale(); }
  std::size_t observations() const { return translation_scale_.observations(); }
  const OdometryNoiseConfig& config() const { return config_; }

  /// The model's sigmas of an increment, unscaled (the configured model, before any learning).
  double sigma_translation(const SE2& increment) const;
  double sigma_rotation(const SE2& increment) const;

 private:
  OdometryNoiseConfig config_;
  NoiseScaleEstimate translation_scale_;
  NoiseScaleEstimate rotation_scale_;
};

/// The mean of a covariance's x and y variances: the variance per translational degree of freedom.
inline double planar_variance(const Covariance3& c) { return 0.5 * (c(0, 0) + c(1, 1)); }

/// b - a in (x, y, theta), the heading's difference wrapped: how far two estimates of one small
/// increment disagree.
Eigen::Vector3d motion_difference(const SE2& a, const SE2& b);

/// A measured increment T_a_b with its covariance (in frame a's coordinates x, y, theta).
struct MotionMeasurement {
  SE2 value;
  Covariance3 covariance = unknown_covariance();
};

/// Which measurement a fusion kept.
enum class FusionOutcome : std::uint8_t {
  kFused,        // consistent: the information-weighted mean
  kOdometryWon,  // they disagree beyond the gate; the odometry is better conditioned along the difference
  kMatchWon,     // they disagree; the match is
};

struct FusedMotion {
  SE2 value;
  Covariance3 covariance = unknown_covariance();
  double mahalanobis2 = 0.0;  // squared distance of the two under the sum of their covariances
  FusionOutcome outcome = FusionOutcome::kFused;
};

/// The chi-square gate with 3 degrees of freedom at 99.9 %.
inline constexpr double kMotionGateChi2 = 16.27;

/// Fuses the two measurements of one motion (header). A measurement with unknown covariance
/// (kUnknownVariance on the diagonal) carries no information: the other is returned.
FusedMotion fuse_motion(const MotionMeasurement& odometry, const MotionMeasurement& match,
                        double gate_chi2 = kMotionGateChi2);

/// Counts of a run's fusions, for summaries.
struct MotionFusionStats {
  std::size_t fused = 0;
  std::size_t odometry_won = 0;  // disagreements the odometry won
  std::size_t match_won = 0;     // disagreements the match won
  void count(FusionOutcome outcome);
  std::size_t disagreements() const { return odometry_won + match_won; }
};

}  // namespace slam2d
