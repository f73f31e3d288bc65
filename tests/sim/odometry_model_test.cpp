// SPDX-License-Identifier: BSD-3-Clause
// The odometry error model: systematic errors by hand, noise variances against the formulas.

#include <gtest/gtest.h>

#include <cmath>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/sim/odometry_model.hpp"

namespace slam2d {
namespace {

OdometryModelConfig noise_free() {
  return {.alpha1 = 0.0, .alpha2 = 0.0, .alpha3 = 0.0, .alpha4 = 0.0, .scale_error = 0.0, .heading_bias = 0.0};
}

TEST(OdometryModel, NoErrorsGiveTheTrueMotion) {
  Rng rng(3);
  for (const SE2& motion : {SE2(0.1, 0.02, 0.3), SE2(0, 0, -0.2), SE2(-0.05, 0.0, 0.0), SE2()}) {
    EXPECT_TRUE(corrupt_motion(motion, noise_free(), &rng).is_approx(motion, 1e-15)) << motion;
  }
}

TEST(OdometryModel, ScaleErrorStretchesTheDistance) {
  OdometryModelConfig config = noise_free();
  config.scale_error = 0.05;
  const SE2 motion(0.3, 0.04, 0.2);
  const SE2 odom = corrupt_motion(motion, config, nullptr);
  EXPECT_NEAR(odom.translation().norm(), 1.05 * motion.translation().norm(), 1e-15);
  EXPECT_NEAR(std::atan2(odom.y(), odom.x()), std::atan2(motion.y(), motion.x()), 1e-15);
  EXPECT_NEAR(odom.theta(), motion.theta(), 1e-15);
}

TEST(OdometryModel, HeadingBiasTurnsPerMetre) {
  OdometryModelConfig config = noise_free();
  config.heading_bias = 0.01;  // rad/m
  const SE2 odom = corrupt_motion(SE2(0.5, 0.0, 0.0), config, nullptr);
  // 0.5 m straight: heading +0.005 rad, half of it before translating.
  EXPECT_NEAR(odom.theta(), 0.005, 1e-15);
  EXPECT_NEAR(odom.x(), 0.5 * std::cos(0.0025), 1e-15);
  EXPECT_NEAR(odom.y(), 0.5 * std::sin(0.0025), 1e-15);
  // A turn on the spot has no translation, so no drift.
  EXPECT_NEAR(corrupt_motion(SE2(0, 0, 0.4), config, nullptr).theta(), 0.4, 1e-15);
}

TEST(OdometryModel, NoiseVariancesAreLinearInTheMotion) {
  // Motion: rot1 = 0.1 rad, trans = 0.2 m, rot2 = 0.3 rad.
  const double rot1 = 0.1, trans = 0.2, rot2 = 0.3;
  const SE2 motion(trans * std::cos(rot1), trans * std::sin(rot1), rot1 + rot2);
  const OdometryModelConfig config{.alpha1 = 1e-3, .alpha2 = 2e-3, .alpha3 = 3e-3, .alpha4 = 4e-3,
                                   .scale_error = 0.0, .heading_bias = 0.0};
  Rng rng(11);
  const int n = 40000;
  double sum[3] = {0, 0, 0}, sum_sq[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const SE2 odom = corrupt_motion(motion, config, &rng);
    const double odom_rot1 = std::atan2(odom.y(), odom.x());
    const double e[3] = {odom_rot1 - rot1, odom.translation().norm() - trans,
                         angle_difference(odom.theta() - odom_rot1, rot2)};
    for (int k = 0; k < 3; ++k) {
      sum[k] += e[k];
      sum_sq[k] += e[k] * e[k];
    }
  }
  const double expected[3] = {1e-3 * rot1 + 2e-3 * trans, 3e-3 * trans + 4e-3 * (rot1 + rot2),
                              1e-3 * rot2 + 2e-3 * trans};
  for (int k = 0; k < 3; ++k) {
    const double mean = sum[k] / n, variance = sum_sq[k] / n - mean * mean;
    EXPECT_NEAR(mean, 0.0, 5.0 * std::sqrt(expected[k] / n)) << k;
    EXPECT_NEAR(variance, expected[k], 0.05 * expected[k]) << k;  // sampling error ~ 0.7 %
  }
}

TEST(OdometryModel, ValidationRejectsBadParameters) {
  EXPECT_NO_THROW(validate(OdometryModelConfig{}));
  OdometryModelConfig config;
  config.alpha2 = -1e-3;
  EXPECT_THROW(validate(config), Error);
  config = {};
  config.rate_hz = 0.0;
  EXPECT_THROW(validate(config), Error);
  config = {};
  config.heading_bias = std::nan("");
  EXPECT_THROW(validate(config), Error);
  config = {};
  config.scale_error = -1.0;
  EXPECT_THROW(validate(config), Error);
}

}  // namespace
}  // namespace slam2d
