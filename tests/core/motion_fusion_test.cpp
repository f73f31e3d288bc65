// SPDX-License-Identifier: BSD-3-Clause
// Odometry and scan match as two measurements of one motion (core/motion_fusion.hpp): the fused
// value is the product of the two Gaussians, a disagreement is won by the measurement surer along
// it, the odometry's noise model learns its scale from the agreements, and its systematic error
// is found from stretches measured at both ends.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "slam2d/core/error.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/rng.hpp"

namespace slam2d {
namespace {

Covariance3 random_covariance(Rng& rng, double scale) {
  Eigen::Matrix3d a;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) a(r, c) = rng.gaussian(0.0, scale);
  }
  return a * a.transpose() + scale * scale * 0.1 * Eigen::Matrix3d::Identity();
}

// The product of two Gaussians in the moment form: x = a + A (A + B)^-1 (b - a), P = A - A (A + B)^-1 A.
TEST(MotionFusion, ConsistentMeasurementsGiveTheProductOfTheirGaussians) {
  Rng rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Covariance3 A = random_covariance(rng, 0.05);
    const Covariance3 B = random_covariance(rng, 0.05);
    const SE2 a(rng.gaussian(0.0, 1.0), rng.gaussian(0.0, 1.0), rng.gaussian(0.0, 1.0));
    const Eigen::Vector3d offset(rng.gaussian(0.0, 0.01), rng.gaussian(0.0, 0.01), rng.gaussian(0.0, 0.01));
    const SE2 b = SE2::from_vector(a.vector() + offset);
    const FusedMotion fused = fuse_motion({a, A}, {b, B});
    ASSERT_EQ(fused.outcome, FusionOutcome::kFused) << trial;
    const Eigen::Matrix3d gain = A * (A + B).inverse();
    const Eigen::Vector3d expected = a.vector() + gain * offset;
    const Covariance3 expected_covariance = A - gain * A;
    EXPECT_TRUE(fused.value.is_approx(SE2::from_vector(expected), 1e-9)) << trial;
    EXPECT_LT((fused.covariance - expected_covariance).norm(), 1e-9 * expected_covariance.norm() + 1e-15) << trial;
    EXPECT_NEAR(fused.mahalanobis2, offset.dot((A + B).inverse() * offset), 1e-9);
  }
}

// A corridor: the match knows y and the heading, not x; the odometry knows x roughly.
TEST(MotionFusion, ADegenerateMatchLeavesItsWeakDirectionToTheOdometry) {
  const MotionMeasurement odometry{SE2(1.0, 0.05, 0.0), covariance_from_sigmas(0.05, 0.05, 0.02)};
  const MotionMeasurement match{SE2(1.3, 0.0, 0.01), covariance_from_sigmas(10.0, 0.002, 0.001)};
  const FusedMotion fused = fuse_motion(odometry, match);
  EXPECT_EQ(fused.outcome, FusionOutcome::kFused);
  EXPECT_NEAR(fused.value.x(), 1.0, 0.001);
  EXPECT_NEAR(fused.value.y(), 0.0, 0.001);
  EXPECT_NEAR(fused.value.theta(), 0.01, 0.001);
}

TEST(MotionFusion, ADisagreementIsWonByTheMeasurementSurerAlongIt) {
  MotionFusionStats stats;
  // A match 1 m off the odometry along x, which the match is sure of and the odometry is not.
  const MotionMeasurement loose_odometry{SE2(1.0, 0.0, 0.0), covariance_from_sigmas(0.1, 0.1, 0.05)};
  const MotionMeasurement sure_match{SE2(2.0, 0.0, 0.0), covariance_from_sigmas(0.01, 0.01, 0.01)};
  const FusedMotion match_wins = fuse_motion(loose_odometry, sure_match);
  EXPECT_EQ(match_wins.outcome, FusionOutcome::kMatchWon);
  EXPECT_EQ(match_wins.value, sure_match.value);
  EXPECT_GT(match_wins.mahalanobis2, kMotionGateChi2);
  stats.count(match_wins.outcome);
  // The same difference along the match's weak direction: the odometry wins.
  const MotionMeasurement sure_odometry{SE2(1.0, 0.0, 0.0), covariance_from_sigmas(0.01, 0.01, 0.01)};
  const MotionMeasurement loose_match{SE2(2.0, 0.0, 0.0), covariance_from_sigmas(0.1, 0.001, 0.001)};
  const FusedMotion odometry_wins = fuse_motion(sure_odometry, loose_match);
  EXPECT_EQ(odometry_wins.outcome, FusionOutcome::kOdometryWon);
  EXPECT_EQ(odometry_wins.value, sure_odometry.value);
  stats.count(odometry_wins.outcome);
  stats.count(FusionOutcome::kFused);
  EXPECT_EQ(stats.disagreements(), 2u);
  EXPECT_EQ(stats.fused, 1u);
}

TEST(MotionFusion, AMeasurementWithoutInformationLeavesTheOther) {
  const MotionMeasurement odometry{SE2(1.0, 0.0, 0.1), covariance_from_sigmas(0.1, 0.1, 0.05)};
  const MotionMeasurement failed{SE2(5.0, 5.0, 1.0), unknown_covariance()};
  EXPECT_EQ(fuse_motion(odometry, failed).value, odometry.value);
  EXPECT_EQ(fuse_motion(failed, odometry).value, odometry.value);
}

TEST(MotionFusion, HeadingsAcrossPiAreFusedTheShortWay) {
  const double near_pi = std::numbers::pi - 0.01;
  const MotionMeasurement odometry{SE2(0.0, 0.0, near_pi), covariance_from_sigmas(0.1, 0.1, 0.05)};
  const MotionMeasurement match{SE2(0.0, 0.0, -near_pi), covariance_from_sigmas(0.1, 0.1, 0.05)};
  const FusedMotion fused = fuse_motion(odometry, match);
  EXPECT_EQ(fused.outcome, FusionOutcome::kFused);
  EXPECT_GT(std::abs(fused.value.theta()), std::numbers::pi - 1e-6);
}

TEST(OdometryNoiseModel, SigmasGrowWithDistanceAndTurn) {
  const OdometryNoiseModel model(OdometryNoiseConfig{.rest_translation = 0.01, .rest_rotation = 0.02,
                                                     .translation_per_metre = 0.1, .translation_per_radian = 0.05,
                                                     .rotation_per_metre = 0.03, .rotation_per_radian = 0.2});
  const Covariance3 at_rest = model.covariance(SE2());
  EXPECT_NEAR(std::sqrt(at_rest(0, 0)), 0.01, 1e-12);
  EXPECT_NEAR(std::sqrt(at_rest(2, 2)), 0.02, 1e-12);
  const Covariance3 moving = model.covariance(SE2(2.0, 0.0, 0.5));
  EXPECT_NEAR(std::sqrt(moving(0, 0)), 0.01 + 0.2 + 0.025, 1e-12);
  EXPECT_NEAR(std::sqrt(moving(1, 1)), 0.01 + 0.2 + 0.025, 1e-12);
  EXPECT_NEAR(std::sqrt(moving(2, 2)), 0.02 + 0.06 + 0.1, 1e-12);
}

// Odometry whose true noise is three times the model's (in translation) and half (in rotation),
// against matches with their own small noise, 5 % of them wrong by a metre: the scales are learnt.
TEST(OdometryNoiseModel, LearnsItsScaleFromAgreementsDespiteWrongMatches) {
  const OdometryNoiseConfig config{.window = 200.0};
  OdometryNoiseModel model(config);
  const OdometryNoiseModel reference(OdometryNoiseConfig{.window = 0.0});
  Rng rng(3);
  const Covariance3 match_covariance = covariance_from_sigmas(0.002, 0.002, 0.001);
  for (int k = 0; k < 3000; ++k) {
    const SE2 truth(0.1 + 0.05 * rng.uniform(), 0.0, 0.1 * rng.gaussian(0.0, 1.0));
    const Covariance3 model_covariance = reference.covariance(truth);
    const double st = 3.0 * std::sqrt(model_covariance(0, 0));
    const double sr = 0.5 * std::sqrt(model_covariance(2, 2));
    const SE2 odometry(truth.x() + rng.gaussian(0.0, st), truth.y() + rng.gaussian(0.0, st), truth.theta() + rng.gaussian(0.0, sr));
    SE2 match(truth.x() + rng.gaussian(0.0, 0.002), truth.y() + rng.gaussian(0.0, 0.002), truth.theta() + rng.gaussian(0.0, 0.001));
    if (rng.uniform() < 0.05) match = match * SE2(1.0, 0.0, 0.3);
    model.observe(odometry, match, match_covariance);
  }
  EXPECT_NEAR(model.translation_scale(), 3.0, 0.45);
  EXPECT_NEAR(model.rotation_scale(), 0.5, 0.1);
  EXPECT_EQ(model.observations(), 3000u);
  // A fixed model (window 0) learns nothing.
  OdometryNoiseModel fixed(OdometryNoiseConfig{.window = 0.0});
  fixed.observe(SE2(1.0, 0.0, 0.0), SE2(2.0, 0.0, 0.0), match_covariance);
  EXPECT_EQ(fixed.translation_scale(), 1.0);
}

// One stretch of a wheel odometry that reads its distances `translation_scale` times too short,
// turns `rotation_scale` times too much and drifts `drift` rad per true metre, measured with noise.
// Now and then the robot drives backwards, and every twentieth stretch is a slip (or a wrong match).
struct SimulatedOdometry {
  double translation_scale = 1.0;
  double rotation_scale = 1.0;
  double drift = 0.0;
  double sigma_xy = 0.01;
  double sigma_theta = 0.008;

  void observe(Rng& rng, int i, OdometryCalibration& calibration) const {
    const double direction = i % 7 == 0 ? -1.0 : 1.0;
    const double path = direction * (0.3 + 0.4 * rng.uniform());  // odometry, signed
    const double turn = rng.gaussian(0.0, 0.3);                    // odometry
    const Eigen::Vector2d displacement(path * std::cos(0.5 * turn), path * std::sin(0.5 * turn));
    const double true_turn = turn / rotation_scale + drift * (translation_scale * path);
    const Eigen::Vector2d measured =
        translation_scale * displacement + Eigen::Vector2d(rng.gaussian(0.0, sigma_xy), rng.gaussian(0.0, sigma_xy));
    double measured_turn = true_turn + rng.gaussian(0.0, sigma_theta);
    if (i % 20 == 5) measured_turn += 0.3;
    calibration.observe(turn, path, displacement, measured_turn, measured, 2.0 * sigma_theta * sigma_theta,
                        2.0 * sigma_xy * sigma_xy);
  }
};

// Stretches of a wheel odometry whose distance is 4 % short, whose turns are 3 % long and which
// turns 0.05 rad per metre it drives (unequal wheels; the other way when it reverses), measured at
// both ends with noise and one stretch in twenty wrong by a slip: the three errors are found.
TEST(OdometryCalibration, FindsTheScalesAndTheDriftOfAWheelOdometry) {
  Rng rng(23);
  OdometryCalibration calibration;
  const SimulatedOdometry odometry{.translation_scale = 1.04, .rotation_scale = 1.03, .drift = 0.05};
  for (int i = 0; i < 600; ++i) odometry.observe(rng, i, calibration);
  EXPECT_EQ(calibration.observations(), 600u);
  EXPECT_NEAR(calibration.translation_scale(), 1.04, 0.005);
  EXPECT_NEAR(calibration.rotation_scale(), 1.0 / 1.03, 0.01);
  // The drift per metre of odometry distance: 0.05 rad per true metre, 1.04 true metres in one.
  EXPECT_NEAR(calibration.drift_per_metre(), 0.05 * 1.04, 0.005);
  // Corrected, an increment of that odometry is the robot's own motion, backwards too.
  for (const double path : {0.5, -0.3}) {
    const double turn = 0.2;
    const SE2 read(path * std::cos(0.5 * turn), path * std::sin(0.5 * turn), turn);
    const double true_turn = turn / 1.03 + 0.05 * 1.04 * path;
    const SE2 robot(1.04 * path * std::cos(0.5 * true_turn), 1.04 * path * std::sin(0.5 * true_turn), true_turn);
    EXPECT_LT(motion_difference(calibration.corrected(read), robot).cwiseAbs().maxCoeff(), 0.008) << path;
  }
}

// Only what stands out of the fit's own uncertainty is corrected. An odometry without systematic
// error: its fit still finds some in the noise of 100 stretches, but none of it is corrected, and
// an increment passes unchanged. One with a large error: corrected nearly whole (the garrote keeps
// 1 - 1/m^2 of an estimate m times its threshold).
TEST(OdometryCalibration, CorrectsOnlyTheErrorThatStandsOutOfItsUncertainty) {
  const OdometryCalibrationConfig config{.window = 1000.0, .significance = 5.0};  // graph SLAM's tracker's
  bool found_some = false;  // whether the raw fit, uncorrected, found an error in the noise
  for (const std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    Rng rng(seed);
    OdometryCalibration exact(config);
    OdometryCalibration raw(OdometryCalibrationConfig{.window = 1000.0});  // the fit as it is
    Rng twin(seed);
    for (int i = 0; i < 100; ++i) {
      SimulatedOdometry{}.observe(rng, i, exact);
      SimulatedOdometry{}.observe(twin, i, raw);
    }
    EXPECT_EQ(exact.translation_scale(), 1.0) << seed;
    EXPECT_EQ(exact.rotation_scale(), 1.0) << seed;
    EXPECT_EQ(exact.drift_per_metre(), 0.0) << seed;
    const SE2 increment(0.4, 0.02, 0.1);
    EXPECT_LT(motion_difference(exact.corrected(increment), increment).norm(), 1e-15) << seed;
    found_some = found_some || std::abs(raw.translation_scale() - 1.0) > 1e-3 || std::abs(raw.drift_per_metre()) > 1e-3;
  }
  EXPECT_TRUE(found_some);
  Rng rng(7);
  OdometryCalibration wheel(config);
  const SimulatedOdometry odometry{.translation_scale = 1.04, .rotation_scale = 1.03, .drift = 0.05};
  for (int i = 0; i < 1000; ++i) odometry.observe(rng, i, wheel);
  EXPECT_NEAR(wheel.translation_scale(), 1.04, 0.003);
  EXPECT_NEAR(wheel.rotation_scale(), 1.0 / 1.03, 0.006);
  EXPECT_NEAR(wheel.drift_per_metre(), 0.05 * 1.04, 0.004);
}

// The stretch a calibration compares: the increments composed, their signed turn and their signed
// path length (backwards negative).
TEST(OdometryStretch, AddsUpTheIncrementsWithTheirSigns) {
  OdometryStretch stretch;
  stretch.add(SE2(0.5, 0.0, 0.3));
  stretch.add(SE2(-0.2, 0.0, -0.1));
  EXPECT_NEAR(stretch.turn, 0.2, 1e-12);
  EXPECT_NEAR(stretch.path, 0.3, 1e-12);
  const SE2 expected = SE2(0.5, 0.0, 0.3) * SE2(-0.2, 0.0, -0.1);
  EXPECT_LT(motion_difference(stretch.displacement, expected).norm(), 1e-12);
}

// A tracker's stretches from its matched poses: a wheel odometry 4 % short, turning 3 % too much
// and drifting 0.052 rad per metre, whose poses also jitter by 6 cm and 0.01 rad (an error that
// does not add up: a time-stamp error, an interpolated log). Everything the fit leans on is the
// measured motion, never the jittering odometry: a stretch ends on the measured span (ended where
// the jitter carried the odometry over it, the odometry's length would be the fixed one), the
// odometry's displacement is taken along the measured one (its length grows with any sideways
// jitter) and the drift is regressed on the measured length (the odometry's path adds up the
// jitter of every increment). Without the three the scale came out 0.993 and the drift 0.037
// rad/m here; with the stretch's end alone 1.014 and 0.037.
TEST(CalibrationStretches, FindTheSystematicErrorThroughAnOdometrysJitter) {
  Rng rng(5);
  OdometryCalibration calibration;
  CalibrationStretches stretches;
  SE2 clean_odometry;  // the odometry without its jitter
  SE2 truth;
  SE2 previous_odometry;
  const Covariance3 measured_covariance = covariance_from_sigmas(0.001, 0.001, 0.0005);
  const Covariance3 increment_noise = covariance_from_sigmas(0.02, 0.02, 0.005);
  for (int k = 0; k < 20000; ++k) {
    const double path = 0.048;                                       // odometry, per scan
    const double turn = (k / 25) % 3 == 0 ? 0.0 : ((k / 75) % 2 == 0 ? 0.04 : -0.03);
    const double true_turn = turn / 1.03 + 0.052 * path;
    const double true_path = 1.04 * path;
    clean_odometry = clean_odometry * SE2(path * std::cos(0.5 * turn), path * std::sin(0.5 * turn), turn);
    truth = truth * SE2(true_path * std::cos(0.5 * true_turn), true_path * std::sin(0.5 * true_turn), true_turn);
    const SE2 odometry = clean_odometry * SE2(rng.gaussian(0.0, 0.06), rng.gaussian(0.0, 0.06), rng.gaussian(0.0, 0.01));
    const SE2 measured = truth * SE2(rng.gaussian(0.0, 0.001), rng.gaussian(0.0, 0.001), rng.gaussian(0.0, 0.0005));
    stretches.add(/*usable=*/k > 0, previous_odometry.between(odometry), increment_noise, measured, measured_covariance,
                  calibration);
    previous_odometry = odometry;
  }
  EXPECT_GT(calibration.observations(), 1500u);
  EXPECT_NEAR(calibration.translation_scale(), 1.04, 0.006);  // measured 1.038
  EXPECT_NEAR(calibration.rotation_scale(), 1.0 / 1.03, 0.01);
  EXPECT_NEAR(calibration.drift_per_metre(), 0.052, 0.005);   // measured 0.0518
}

// A scan that is not usable (an increment the guard did not trust, no match) ends the stretch
// unlearnt, and the next usable one starts a new stretch.
TEST(CalibrationStretches, AnUnusableScanEndsTheStretchUnlearnt) {
  OdometryCalibration calibration;
  CalibrationStretches stretches;
  const Covariance3 covariance = covariance_from_sigmas(0.01, 0.01, 0.01);
  SE2 pose;
  for (int k = 0; k < 100; ++k) {  // 0.11 m a scan; every fourth scan unusable: never 0.5 m in a row
    pose = pose * SE2(0.11, 0.0, 0.0);
    stretches.add(k % 4 != 0, SE2(0.11, 0.0, 0.0), covariance, pose, covariance, calibration);
  }
  EXPECT_EQ(calibration.observations(), 0u);
  for (int k = 0; k < 12; ++k) {  // then twelve usable scans: the first anchors, every fifth ends a stretch (0.55 m)
    pose = pose * SE2(0.11, 0.0, 0.0);
    stretches.add(true, SE2(0.11, 0.0, 0.0), covariance, pose, covariance, calibration);
  }
  EXPECT_EQ(calibration.observations(), 2u);
}

TEST(OdometryCalibration, AWindowOfZeroCorrectsNothing) {
  OdometryCalibration calibration(OdometryCalibrationConfig{.window = 0.0});
  for (int i = 0; i < 100; ++i) {
    calibration.observe(0.1, 0.5, Eigen::Vector2d(0.5, 0.0), 0.3, Eigen::Vector2d(0.6, 0.0), 1e-4, 1e-4);
  }
  EXPECT_EQ(calibration.observations(), 0u);
  EXPECT_EQ(calibration.translation_scale(), 1.0);
  EXPECT_EQ(calibration.rotation_scale(), 1.0);
  EXPECT_EQ(calibration.drift_per_metre(), 0.0);
}

TEST(OdometryNoiseModel, RejectsAnInvalidConfig) {
  EXPECT_THROW(OdometryNoiseModel(OdometryNoiseConfig{.rest_translation = 0.0}), Error);
  EXPECT_THROW(OdometryNoiseModel(OdometryNoiseConfig{.min_scale = 2.0}), Error);
  EXPECT_THROW(OdometryNoiseModel(OdometryNoiseConfig{.max_scale = 0.5}), Error);
}

}  // namespace
}  // namespace slam2d
