// SPDX-License-Identifier: BSD-3-Clause
// The localization models: the odometry motion model's Jacobians against finite differences, its
// samples against its covariance, the KLD bound, the beam model's ray casting on a hand-made map,
// and the scan-to-map matcher recovering a known offset.

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/localization/localization_map.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/localization/motion_model.hpp"
#include "slam2d/registration/likelihood_field_match.hpp"
#include "slam2d/localization/sensor_model.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

Eigen::Vector3d difference(const SE2& a, const SE2& b) {
  return {a.x() - b.x(), a.y() - b.y(), angle_difference(a.theta(), b.theta())};
}

TEST(OdometryMotionModel, DecomposeThenApplyGivesTheOdometryMotion) {
  const SE2 previous(1.0, -2.0, 0.3);
  const SE2 current(1.8, -1.5, 1.2);
  const OdometryControl u = decompose_odometry(previous, current);
  EXPECT_NEAR(u.trans, std::hypot(0.8, 0.5), 1e-12);
  EXPECT_NEAR(u.rot1, std::atan2(0.5, 0.8) - 0.3, 1e-12);
  EXPECT_TRUE(test::poses_near(apply_odometry(previous, u), current, 1e-12, 1e-12));
  // From another start pose the same control moves the robot the same way in its own frame.
  const SE2 other(-3.0, 4.0, -2.0);
  EXPECT_TRUE(test::poses_near(other.between(apply_odometry(other, u)), previous.between(current), 1e-12, 1e-12));
}

TEST(OdometryMotionModel, JacobiansMatchFiniteDifferences) {
  const SE2 pose(0.5, -1.0, 2.5);
  const OdometryControl u{.rot1 = 0.4, .trans = 0.7, .rot2 = -0.9};
  Matrix3 J_pose;
  Matrix3 J_control;
  const SE2 result = apply_odometry(pose, u, &J_pose, &J_control);
  const double h = 1e-6;
  for (int j = 0; j < 3; ++j) {
    Eigen::Vector3d dx = Eigen::Vector3d::Zero();
    dx(j) = h;
    const SE2 moved = apply_odometry(SE2::from_vector(pose.vector() + dx), u);
    const Eigen::Vector3d numeric = difference(moved, result) / h;
    EXPECT_LT((numeric - J_pose.col(j)).norm(), 1e-5) << "state column " << j;
    Eigen::Vector3d du = u.vector();
    du(j) += h;
    const SE2 moved_u = apply_odometry(pose, OdometryControl{du(0), du(1), du(2)});
    const Eigen::Vector3d numeric_u = difference(moved_u, result) / h;
    EXPECT_LT((numeric_u - J_control.col(j)).norm(), 1e-5) << "control column " << j;
  }
}

TEST(OdometryMotionModel, SampleStatisticsMatchThePredictedCovariance) {
  const SE2 pose(2.0, 1.0, 0.7);
  const Covariance3 prior = covariance_from_sigmas(0.05, 0.03, 0.02);
  const OdometryControl u{.rot1 = 0.2, .trans = 0.5, .rot2 = -0.1};
  const OdometryMotionConfig config{.alpha1 = 0.02, .alpha2 = 0.01, .alpha3 = 0.02, .alpha4 = 0.01};
  const MotionPrediction prediction = predict_odometry_motion(pose, prior, u, config);
  Rng rng(7);
  const Eigen::Matrix3d L = prior.llt().matrixL();
  const int n = 40000;
  std::vector<Eigen::Vector3d> offsets;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d e = L * Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian());
    const SE2 start = SE2::from_vector(pose.vector() + e);
    offsets.push_back(difference(sample_odometry_motion(start, u, config, rng), prediction.pose));
    mean += offsets.back() / n;
  }
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& d : offsets) covariance += (d - mean) * (d - mean).transpose() / (n - 1);
  // The mean is the noise-free motion (to first order), the spread the EKF's covariance.
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(mean(i), 0.0, 4.0 * std::sqrt(prediction.covariance(i, i) / n) + 2e-3) << i;
    EXPECT_NEAR(covariance(i, i), prediction.covariance(i, i), 0.05 * prediction.covariance(i, i)) << i;
  }
  const double rho_sample = covariance(0, 2) / std::sqrt(covariance(0, 0) * covariance(2, 2));
  const double rho_model = prediction.covariance(0, 2) / std::sqrt(prediction.covariance(0, 0) * prediction.covariance(2, 2));
  EXPECT_NEAR(rho_sample, rho_model, 0.03);
}

TEST(OdometryMotionModel, BackwardDrivingIsNotAHalfTurnOfNoise) {
  const OdometryMotionConfig config;
  const SE2 start(0.0, 0.0, 0.0);
  const OdometryControl backward = decompose_odometry(start, SE2(-0.5, 0.0, 0.0));
  const OdometryControl forward = decompose_odometry(start, SE2(0.5, 0.0, 0.0));
  EXPECT_NEAR(std::abs(backward.rot1), std::numbers::pi, 1e-12);
  EXPECT_TRUE(control_covariance(backward, config).isApprox(control_covariance(forward, config), 1e-12));
}

// A robot driving a winding path; its odometry moves by controls perturbed with k_t (k_r) times
// the model's translation (rotation) noise, its pose measured every step with known noise. The
// learner finds k_t and k_r, each apart: a heading error moves the robot sideways, and that share
// is the rotation's, not the translation's.
TEST(MotionNoiseLearner, FindsTheScalesOfTheOdometrysNoise) {
  const OdometryMotionConfig model;
  const MotionNoiseLearningConfig learning{.window = 100.0, .min_scale = 0.2, .max_scale = 20.0};
  const double measured_xy = 0.01;
  const double measured_theta = 0.005;
  for (const auto& [k_t, k_r] : {std::pair{3.0, 3.0}, std::pair{0.6, 0.6}, std::pair{3.0, 0.7}, std::pair{0.7, 3.0}}) {
    Rng rng(11);
    MotionNoiseLearner learner(model, learning);
    SE2 truth;
    SE2 odometry;
    for (int i = 0; i < 6000; ++i) {
      const OdometryControl u{.rot1 = 0.05 * rng.gaussian(), .trans = 0.05, .rot2 = 0.05 * rng.gaussian()};
      const Eigen::Vector3d sigma = control_covariance(u, model).diagonal().cwiseSqrt();
      const OdometryControl noisy{.rot1 = u.rot1 + k_r * sigma(0) * rng.gaussian(),
                                  .trans = u.trans + k_t * sigma(1) * rng.gaussian(),
                                  .rot2 = u.rot2 + k_r * sigma(2) * rng.gaussian()};
      const SE2 next_odometry = apply_odometry(odometry, noisy);
      learner.move(odometry.between(next_odometry));
      odometry = next_odometry;
      truth = apply_odometry(truth, u);
      const SE2 measured(truth.x() + measured_xy * rng.gaussian(), truth.y() + measured_xy * rng.gaussian(),
                         truth.theta() + measured_theta * rng.gaussian());
      learner.measured(measured, covariance_from_sigmas(measured_xy, measured_xy, measured_theta));
    }
    EXPECT_GT(learner.stretches(), 400u);
    EXPECT_NEAR(learner.translation_scale(), k_t, 0.2 * k_t) << k_t << " " << k_r;
    EXPECT_NEAR(learner.rotation_scale(), k_r, 0.2 * k_r) << k_t << " " << k_r;
    // The model it hands the filter is the one the odometry was drawn from, up to the estimate.
    EXPECT_NEAR(learner.model().alpha3 / model.alpha3, learner.translation_scale() * learner.translation_scale(), 1e-12);
    EXPECT_NEAR(learner.model().alpha1 / model.alpha1, learner.rotation_scale() * learner.rotation_scale(), 1e-12);
  }
}

TEST(MotionNoiseLearner, AWindowOfZeroKeepsTheModel) {
  const OdometryMotionConfig model;
  MotionNoiseLearner learner(model, MotionNoiseLearningConfig{.window = 0.0, .calibration = {.window = 0.0}});
  SE2 odometry;
  for (int i = 0; i < 100; ++i) {
    const SE2 next = odometry * SE2(0.1, 0.0, 0.0);
    learner.move(odometry.between(next));
    odometry = next;
    learner.measured(SE2(0.3 * i, 0.0, 0.0), covariance_from_sigmas(0.01, 0.01, 0.01));  // 3x the odometry's motion
  }
  EXPECT_EQ(learner.stretches(), 0u);
  EXPECT_EQ(learner.model().alpha3, model.alpha3);
  EXPECT_EQ(learner.model().alpha1, model.alpha1);
  EXPECT_EQ(learner.corrected(SE2(0.1, 0.02, 0.05)), SE2(0.1, 0.02, 0.05));
}

// An odometry that reads 5 % short and turns 0.06 rad per metre it drives (the Intel log's is
// 0.058), the robot's pose measured every step: once learnt, the corrected increments are the
// robot's, and the noise scales learn the noise alone, not the systematic error.
TEST(MotionNoiseLearner, CorrectsTheOdometrysSystematicError) {
  const OdometryMotionConfig model;
  Rng rng(29);
  MotionNoiseLearner learner(model, MotionNoiseLearningConfig{.calibration = {.window = 100.0}});
  MotionNoiseLearner fixed(model, MotionNoiseLearningConfig{});  // the default: no calibration
  SE2 truth;
  SE2 odometry;
  double worst = 0.0;
  for (int i = 0; i < 4000; ++i) {
    const SE2 step(0.05, 0.0, 0.05 * std::sin(0.01 * i));  // the robot's
    const SE2 read(0.05 / 1.05, 0.0, step.theta() - 0.06 * 0.05 / 1.05);
    if (i > 2000) worst = std::max(worst, motion_difference(learner.corrected(read), step).cwiseAbs().maxCoeff());
    learner.move(read);
    fixed.move(read);
    odometry = odometry * read;
    truth = truth * step;
    const SE2 measured(truth.x() + 0.01 * rng.gaussian(), truth.y() + 0.01 * rng.gaussian(), truth.theta() + 0.005 * rng.gaussian());
    learner.measured(measured, covariance_from_sigmas(0.01, 0.01, 0.005));
    fixed.measured(measured, covariance_from_sigmas(0.01, 0.01, 0.005));
  }
  EXPECT_NEAR(learner.calibration().translation_scale(), 1.05, 0.01);
  EXPECT_NEAR(learner.calibration().drift_per_metre(), 0.06, 0.006);  // per metre of odometry
  EXPECT_LT(worst, 0.002);  // m and rad per 5 cm step
  // Without the correction the systematic error is taken for noise.
  EXPECT_GT(fixed.rotation_scale(), 1.5 * learner.rotation_scale());
}

TEST(KldSampling, BoundMatchesFoxEquation10) {
  // k = 100, eps = 0.05, z = 2.326: 99 / 0.1 * (1 - 2/891 + sqrt(2/891) 2.326)^3 = 1346.6.
  EXPECT_EQ(kld_particle_count(100, 0.05, 2.326), 1347u);
  EXPECT_EQ(kld_particle_count(1, 0.05, 2.326), 1u);
  EXPECT_LT(kld_particle_count(10, 0.05, 2.326), kld_particle_count(20, 0.05, 2.326));
}

// A 10 m x 10 m room at 0.1 m: walls on the border cells, free inside.
// A free map of width x height cells.
OccupancyMap free_map(double resolution, const SE2& origin, int width, int height) {
  OccupancyMap map;
  map.resolution = resolution;
  map.origin = origin;
  map.width = width;
  map.height = height;
  map.cells.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), OccupancyMap::kFree);
  return map;
}

OccupancyMap room() {
  OccupancyMap map = free_map(0.1, SE2(-5.0, -5.0, 0.0), 100, 100);
  for (int i = 0; i < 100; ++i) {
    map.at(i, 0) = map.at(i, 99) = map.at(0, i) = map.at(99, i) = OccupancyMap::kOccupied;
  }
  return map;
}

TEST(BeamModel, RayCastingHitsTheWalls) {
  const OccupancyMap map = room();
  // From the centre the east wall cell (99) has its centre at x = 4.95.
  EXPECT_NEAR(cast_ray(map, {0.0, 0.0}, 0.0, 20.0), 4.95, 0.06);
  EXPECT_NEAR(cast_ray(map, {1.0, 2.0}, std::numbers::pi / 2, 20.0), 2.95, 0.06);
  EXPECT_NEAR(cast_ray(map, {0.0, 0.0}, 0.0, 3.0), 3.0, 1e-12);  // nothing within the range
}

LaserScan scan_in_room(const OccupancyMap& map, const SE2& pose, int beams) {
  LaserScan scan;
  scan.angle_min = -std::numbers::pi / 2;
  scan.angle_increment = std::numbers::pi / (beams - 1);
  scan.range_max = 20.0;
  for (int i = 0; i < beams; ++i) scan.ranges.push_back(cast_ray(map, pose.translation(), pose.theta() + scan.angle(i), 20.0));
  return scan;
}

TEST(BeamModel, TheTruePoseScoresBestAndMaxRangeReadingsCount) {
  const OccupancyMap map = room();
  const SE2 truth(1.0, -0.5, 0.3);
  const ScanBeams beams = select_beams(scan_in_room(map, truth, 181), 60, 30.0);
  EXPECT_EQ(beams.ranges.size(), 60u);
  const BeamModelConfig config;
  const double best = beam_model_log_likelihood(map, beams, truth, config);
  for (const SE2& offset : {SE2(0.3, 0.0, 0.0), SE2(0.0, -0.3, 0.0), SE2(0.0, 0.0, 0.1)}) {
    EXPECT_GT(best, beam_model_log_likelihood(map, beams, truth * offset, config) + 5.0);
  }
  // A scan whose beams all read max range: likelier where nothing is in range than facing a wall.
  LaserScan empty = scan_in_room(map, truth, 31);
  for (double& r : empty.ranges) r = empty.range_max;
  const ScanBeams none = select_beams(empty, 30, 4.0);
  EXPECT_TRUE(none.points_robot.empty());
  EXPECT_EQ(none.ranges.size(), 30u);
  EXPECT_GT(beam_model_log_likelihood(map, none, SE2(0.0, 0.0, 0.0), config),
            beam_model_log_likelihood(map, none, SE2(3.5, 0.0, 0.0), config));
}

TEST(LikelihoodFieldModel, TheTruePoseScoresBestAndPlausibilityIsOne) {
  const LocalizationMap map(room());
  const SE2 truth(1.0, -0.5, 0.3);
  const ScanBeams beams = select_beams(scan_in_room(map.map(), truth, 181), 60, 30.0);
  const double best = map.scan_log_likelihood(beams.points_robot, truth);
  for (const SE2& offset : {SE2(0.3, 0.0, 0.0), SE2(0.0, -0.3, 0.0), SE2(0.0, 0.0, 0.1)}) {
    EXPECT_GT(best, map.scan_log_likelihood(beams.points_robot, truth * offset) + 5.0);
  }
  EXPECT_DOUBLE_EQ(map.plausibility(beams.points_robot, truth, 0.2), 1.0);
  EXPECT_LT(map.plausibility(beams.points_robot, truth * SE2(0.0, 0.0, 0.5), 0.2), 0.5);
  // Free-pose samples stand in free cells.
  Rng rng(3);
  for (int i = 0; i < 100; ++i) EXPECT_TRUE(map.is_free(map.sample_free_pose(rng).translation()));
}

TEST(LikelihoodFieldModel, TheBatchOverPosesGivesEachPoseItsOwnValue) {
  const LocalizationMap map(room());
  const SE2 truth(1.0, -0.5, 0.3);
  const ScanBeams beams = select_beams(scan_in_room(map.map(), truth, 181), 60, 30.0);
  // More poses than one block of the batch, some off the map, around and far from the truth.
  Rng rng(5);
  std::vector<SE2> poses;
  for (int i = 0; i < 600; ++i) {
    poses.push_back(i % 7 == 0 ? SE2(rng.uniform(-9.0, 9.0), rng.uniform(-9.0, 9.0), rng.uniform(-3.0, 3.0))
                               : truth * SE2(rng.gaussian(0.0, 0.2), rng.gaussian(0.0, 0.2), rng.gaussian(0.0, 0.1)));
  }
  std::vector<double> batch;
  map.scan_log_likelihoods(beams.points_robot, poses, batch);
  ASSERT_EQ(batch.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(batch[i], map.scan_log_likelihood(beams.points_robot, poses[i])) << i;
  const std::size_t best = static_cast<std::size_t>(std::max_element(batch.begin(), batch.end()) - batch.begin());
  EXPECT_LT((poses[best].translation() - truth.translation()).norm(), 0.5) << "the best pose is one near the truth";
}

TEST(LikelihoodFieldMatch, RecoversAKnownOffset) {
  const LocalizationMap map(room());
  const SE2 truth(1.0, -0.5, 0.3);
  const ScanBeams beams = select_beams(scan_in_room(map.map(), truth, 361), 120, 30.0);
  const MatchResult result = match_likelihood_field(map.field(), beams.points_robot, truth * SE2(0.15, -0.1, 0.05));
  EXPECT_TRUE(result.converged);
  EXPECT_TRUE(test::poses_near(result.T_target_source, truth, 0.03, 0.01)) << result.T_target_source;
  EXPECT_GT(result.inlier_fraction, 0.95);
  EXPECT_LT(std::sqrt(result.covariance(0, 0)), 0.05);
  EXPECT_FALSE(result.degenerate) << "a room's corner constrains every direction";
}

// Two parallel walls 2 m apart, their ends out of a 4 m scanner's reach: the fit pins y and the
// heading, not x. The match says so (degenerate, weak direction along x) and its covariance is
// widest along x.
TEST(LikelihoodFieldMatch, ACorridorIsDegenerateAlongItsAxis) {
  OccupancyMap corridor = free_map(0.05, SE2(-10.0, -2.0, 0.0), 400, 80);
  for (int i = 0; i < 400; ++i) corridor.at(i, 20) = corridor.at(i, 60) = OccupancyMap::kOccupied;  // y = -1, +1
  const LocalizationMap map(corridor);
  const SE2 truth(0.0, 0.1, 0.05);
  LaserScan scan = scan_in_room(map.map(), truth, 181);
  for (double& r : scan.ranges) r = std::min(r, 20.0);
  const ScanBeams beams = select_beams(scan, 120, 4.0);
  const MatchResult result = match_likelihood_field(map.field(), beams.points_robot, truth * SE2(0.0, 0.05, 0.02));
  EXPECT_TRUE(result.degenerate);
  EXPECT_GT(std::abs(result.weak_direction.x()), 0.95) << result.weak_direction.transpose();
  EXPECT_NEAR(result.T_target_source.y(), truth.y(), 0.02);
  EXPECT_GT(result.covariance(0, 0), 100.0 * result.covariance(1, 1));
}

}  // namespace
}  // namespace slam2d
