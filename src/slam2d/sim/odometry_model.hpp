// SPDX-License-Identifier: BSD-3-Clause
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

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OdometryModelConfig {
  double alpha1 = 1e-4;
  double alpha2 = 2e-5;
  double alpha3 = 1e-4;
  double alpha4 = 1e-5;
  double scale_error = 0.01;
  double heading_bias = 0.001;
  double rate_hz = 20.0;
};

template <typename Fields>
void describe(Fields& f, OdometryModelConfig& c) {
  f.number("alpha1", c.alpha1, "rad^2 per rad turned", at_least(0), "rotation noise from rotation");
  f.number("alpha2", c.alpha2, "rad^2 per m driven", at_least(0), "rotation noise from translation");
  f.number("alpha3", c.alpha3, "m^2 per m driven", at_least(0), "translation noise from translation");
  f.number("alpha4", c.alpha4, "m^2 per rad turned", at_least(0), "translation noise from rotation");
  f.number("scale_error", c.scale_error, "1", greater_than(-1), "odometry reports (1 + scale_error) x the distance driven");
  f.number("heading_bias", c.heading_bias, "rad per m driven", any_value(),
           "counter-clockwise drift of the odometry heading");
  f.number("rate_hz", c.rate_hz, "Hz", greater_than(0), "ODOM messages (noise is drawn once per message interval)");
}

/// Throws Error unless every field is finite, alphas >= 0, scale_error > -1 and rate_hz > 0.
void validate(const OdometryModelConfig& config);

/// The odometry's version of the true motion `T_prev_curr` (robot frame at the previous reading):
/// systematic errors always, random noise only when `rng` is given.
SE2 corrupt_motion(const SE2& T_prev_curr, const OdometryModelConfig& config, Rng* rng);

}  // namespace slam2d
