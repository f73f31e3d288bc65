#pragma once
// Wheel odometry error model: the odometry motion model of Thrun, Burgard & Fox, "Probabilistic
// Robotics" (2005), Sec. 5.4 / Table 5.6, plus the systematic errors of real wheels.
//
// A motion is split into rotate (delta_rot1), translate (delta_trans), rotate (delta_rot2), and
// each part gets zero-mean Gaussian noise. Unlike the book, whose variances are quadratic in the
// motion (alpha1 delta_rot1^2 + ...), the variances here are linear in it, so noise accumulates
// as a random walk in distance and angle and does not depend on the odometry rate:
//   var(rot1)  = alpha1 |delta_rot1| + alpha2 delta_trans          (same for rot2)
//   var(trans) = alpha3 delta_trans  + alpha4 (|delta_rot1| + |delta_rot2|)
// Systematic errors: the distance is scaled by (1 + scale_error) and the heading drifts by
// heading_bias per metre driven.

#include "slam2d/core/rng.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OdometryModelConfig {
  double alpha1 = 1e-4;         // rad^2 per rad turned: rotation noise from rotation
  double alpha2 = 2e-5;         // rad^2 per m driven: rotation noise from translation
  double alpha3 = 1e-4;         // m^2 per m driven: translation noise from translation
  double alpha4 = 1e-5;         // m^2 per rad turned: translation noise from rotation
  double scale_error = 0.01;    // 1, odometry reports (1 + scale_error) x the distance driven
  double heading_bias = 0.001;  // rad per m driven, counter-clockwise drift of the odometry heading
  double rate_hz = 20.0;        // Hz, ODOM messages (noise is drawn once per message interval)
};

/// Throws Error unless every field is finite, alphas >= 0, scale_error > -1 and rate_hz > 0.
void validate(const OdometryModelConfig& config);

/// The odometry's version of the true motion `T_prev_curr` (robot frame at the previous reading):
/// systematic errors always, random noise only when `rng` is given.
SE2 corrupt_motion(const SE2& T_prev_curr, const OdometryModelConfig& config, Rng* rng);

}  // namespace slam2d
