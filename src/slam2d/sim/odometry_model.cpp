// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/odometry_model.hpp"

#include <cmath>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr double kMinTranslation = 1e-9;  // m, below this the motion is a turn on the spot

double sample_with_variance(Rng* rng, double variance) {
  if (rng == nullptr || variance <= 0.0) return 0.0;
  return rng->gaussian(0.0, std::sqrt(variance));
}

}  // namespace

void validate(const OdometryModelConfig& config) { check_fields(config, "OdometryModelConfig"); }

SE2 corrupt_motion(const SE2& T_prev_curr, const OdometryModelConfig& config, Rng* rng) {
  // Decompose into rotate-translate-rotate (Table 5.6, lines 2-4).
  const double trans = T_prev_curr.translation().norm();
  const double rot1 = trans > kMinTranslation ? std::atan2(T_prev_curr.y(), T_prev_curr.x()) : 0.0;
  const double rot2 = angle_difference(T_prev_curr.theta(), rot1);
  // Noise (lines 5-7, with variances linear in the motion), drawn in a fixed order.
  const double noise_rot1 = sample_with_variance(rng, config.alpha1 * std::abs(rot1) + config.alpha2 * trans);
  const double noise_trans =
      sample_with_variance(rng, config.alpha3 * trans + config.alpha4 * (std::abs(rot1) + std::abs(rot2)));
  const double noise_rot2 = sample_with_variance(rng, config.alpha1 * std::abs(rot2) + config.alpha2 * trans);
  // Systematic errors: wheel scale on the distance, heading drift split over both rotations.
  const double drift = 0.5 * config.heading_bias * trans;
  const double odom_rot1 = rot1 + noise_rot1 + drift;
  const double odom_trans = (1.0 + config.scale_error) * trans + noise_trans;
  const double odom_rot2 = rot2 + noise_rot2 + drift;
  // Recompose (lines 8-10).
  return SE2(odom_trans * std::cos(odom_rot1), odom_trans * std::sin(odom_rot1), odom_rot1 + odom_rot2);
}

}  // namespace slam2d
