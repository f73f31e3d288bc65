// SPDX-License-Identifier: BSD-3-Clause
// Rao-Blackwellized particle filter SLAM: N_eff and low-variance resampling against hand-computed
// cases, the proposal's densities and likelihood lookup, one particle on a noiseless simulator
// reducing to scan matching, determinism, the written path through the update poses, copy-on-write
// map sharing, and the simulated office loop closed with 30 particles.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/eval/ate.hpp"
#include "slam2d/eval/rpe.hpp"
#include "slam2d/grid/bilinear.hpp"
#include "slam2d/sim/fault_injection.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/core/scan_preprocessing.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"
#include "slam2d/core/resampling.hpp"
#include "slam2d/registration/occupancy_gradient_match.hpp"
#include "support/simulated_office.hpp"

namespace slam2d {
namespace {

RbpfSlam run_rbpf(const SimulatedRun& run, const RbpfConfig& config) {
  RbpfSlam slam(config);
  for (const LaserMessage* laser : laser_messages(run)) slam.add_scan(laser->scan, laser->odom_pose);
  return slam;
}

TEST(Resampling, EffectiveSampleSizeOfHandCases) {
  EXPECT_DOUBLE_EQ(effective_sample_size({0.25, 0.25, 0.25, 0.25}), 4.0);
  EXPECT_DOUBLE_EQ(effective_sample_size({1.0, 0.0, 0.0, 0.0}), 1.0);
  EXPECT_NEAR(effective_sample_size({0.5, 0.25, 0.25, 0.0}), 1.0 / 0.375, 1e-12);  // 1 / (1/4 + 1/16 + 1/16)
  EXPECT_THROW(effective_sample_size({}), Error);
}

TEST(Resampling, NormalizesLogWeightsOfAnyMagnitude) {
  for (const double offset : {0.0, -1000.0, 1000.0}) {
    const std::vector<double> w = normalized_weights({offset, offset + std::log(3.0)});
    EXPECT_NEAR(w[0], 0.25, 1e-12);
    EXPECT_NEAR(w[1], 0.75, 1e-12);
  }
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(normalized_weights({-inf, 0.0}), (std::vector<double>{0.0, 1.0}));
  EXPECT_EQ(normalized_weights({-inf, -inf}), (std::vector<double>{0.5, 0.5}));
  EXPECT_THROW(normalized_weights({std::nan(""), 0.0}), Error);
}

TEST(Resampling, LowVarianceMatchesHandComputedDraws) {
  // Pointers 0.125, 0.375, 0.625, 0.875 over the cumulative weights 0.1, 0.3, 0.6, 1.0.
  const std::vector<double> weights{0.1, 0.2, 0.3, 0.4};
  EXPECT_EQ(low_variance_resample(weights, 0.125), (std::vector<std::size_t>{1, 2, 3, 3}));
  // Pointers 0.01, 0.26, 0.51, 0.76.
  EXPECT_EQ(low_variance_resample(weights, 0.01), (std::vector<std::size_t>{0, 1, 2, 3}));
  // Equal weights keep every particle once, whatever r.
  EXPECT_EQ(low_variance_resample({0.25, 0.25, 0.25, 0.25}, 0.2), (std::vector<std::size_t>{0, 1, 2, 3}));
  // All the weight on one particle.
  EXPECT_EQ(low_variance_resample({0.0, 1.0, 0.0}, 0.3), (std::vector<std::size_t>{1, 1, 1}));
  EXPECT_THROW(low_variance_resample(weights, 0.25), Error);
  EXPECT_THROW(low_variance_resample(weights, -0.01), Error);
  // A particle of weight w gets floor(N w) or ceil(N w) copies for any r.
  Rng rng(3);
  const std::vector<double> w{0.05, 0.15, 0.5, 0.3};
  for (int trial = 0; trial < 50; ++trial) {
    const std::vector<std::size_t> drawn = low_variance_resample(w, rng);
    for (std::size_t i = 0; i < w.size(); ++i) {
      const auto copies = static_cast<double>(std::count(drawn.begin(), drawn.end(), i));
      EXPECT_GE(copies, std::floor(4.0 * w[i]));
      EXPECT_LE(copies, std::ceil(4.0 * w[i]));
    }
  }
}

TEST(Proposal, MotionDensityIsANormalisedGaussian) {
  const Eigen::Vector3d sigmas(0.1, 0.1, 0.05);
  const SE2 predicted(1.0, 2.0, 0.5);
  const double peak = -1.5 * std::log(2.0 * std::numbers::pi) - std::log(0.1 * 0.1 * 0.05);
  EXPECT_NEAR(log_motion_density(predicted, predicted, sigmas), peak, 1e-12);
  // One sigma along the predicted pose's own y axis costs exactly 1/2.
  EXPECT_NEAR(log_motion_density(predicted * SE2(0.0, 0.1, 0.0), predicted, sigmas), peak - 0.5, 1e-12);
  EXPECT_NEAR(log_motion_density(predicted * SE2(0.0, 0.0, -0.1), predicted, sigmas), peak - 2.0, 1e-12);
  // Sigmas grow with the motion and never fall below the floors.
  const RbpfMotionNoise noise;
  EXPECT_EQ(motion_sigmas(SE2(), noise), Eigen::Vector3d(noise.min_sigma_translation, noise.min_sigma_translation,
                                                         noise.min_sigma_rotation));
  const Eigen::Vector3d moved = motion_sigmas(SE2(1.0, 0.0, 0.5), noise);
  EXPECT_NEAR(moved.x(), noise.srr * 1.0 + noise.srt * 0.5, 1e-12);
  EXPECT_NEAR(moved.z(), noise.str * 1.0 + noise.stt * 0.5, 1e-12);
  // An update's spread is the same under the caps, and capped above them: a 40 m step over a gap
  // in the scans spreads the particles as a 2 m one (the per-scan prior keeps the model's sigmas).
  EXPECT_EQ(update_sigmas(SE2(1.0, 0.0, 0.5), noise), moved);
  EXPECT_EQ(update_sigmas(SE2(40.0, 3.0, 2.5), noise), Eigen::Vector3d(noise.max_sigma_translation,
                                                                      noise.max_sigma_translation,
                                                                      noise.max_sigma_rotation));
  EXPECT_EQ(update_sigmas(SE2(40.0, 3.0, 2.5), noise), update_sigmas(SE2(2.0, 0.0, 0.0), noise));
  EXPECT_GT(motion_sigmas(SE2(40.0, 3.0, 2.5), noise).x(), 1.0);
}

// The hospital world's plain corridor (sim/hospital_world.hpp: no recess from x = 30 to 60 m, the
// next one beyond the 25 m range): a map from one scan, then the proposal for the scan taken 0.2 m
// farther, predicted at its true pose. The map holds the far walls as the first scan's dots; the
// likelihood, read on the grid of poses around x*, is higher 2 cm back towards them, so the fitted
// mean moved back along the axis at each update (0.46 m over 13 m in the filter). The scan's
// geometry says nothing along the axis: the mean stays with the prediction there.
TEST(Proposal, AlongACorridorsOpenAxisTheMeanIsThePredictions) {
  const SimulatedRun run = simulate(test::hospital_simulation(100.0));
  const std::vector<const LaserMessage*> lasers = laser_messages(run);
  std::size_t first = 0;
  while (first < lasers.size() && run.truth[first].pose.x() < 37.0) ++first;
  ASSERT_LT(first + 1, lasers.size());
  const SE2 mapped = run.truth[first].pose;
  const SE2 truth = run.truth[first + 1].pose;
  ASSERT_LT(truth.x(), 40.0);
  ASSERT_NEAR(mapped.between(truth).x(), 0.2, 0.03);
  const RbpfConfig filter;
  MapPyramidConfig map_config = filter.map;
  map_config.grid.max_range = filter.max_range;
  MapPyramid map(map_config);
  map.integrate_scan(lasers[first]->scan, mapped);
  const std::vector<Eigen::Vector2d> points = usable_end_points(lasers[first + 1]->scan, filter.min_range, filter.max_range);
  const Eigen::Vector3d sigmas = update_sigmas(mapped.between(truth), filter.motion);
  ASSERT_TRUE(scan_open_translation(points, filter.proposal.matcher).has_value());
  const ProposalResult proposal = improved_proposal(map, points, truth, sigmas, filter.proposal);
  ASSERT_TRUE(proposal.matched);
  const SE2 mean = proposal_mean(proposal, truth);
  RecordProperty("along_axis_um", static_cast<int>(1e6 * (mean.x() - truth.x())));
  EXPECT_NEAR(mean.x(), truth.x(), 0.001);  // 2.0 cm back before
  EXPECT_NEAR(mean.y(), truth.y(), 0.01);
}

// A noiseless laser, odometry with only a systematic drift: one particle's filter is scan
// matching against its own map, and recovers the true path far better than the odometry.
// The likelihood's own bilinear lookup (logistic table, no gradient) against interpolate_occupancy,
// at the scan's pose and off it (end points in unknown cells, on tile borders), and its stride.
TEST(Proposal, ObservationLikelihoodMatchesBilinearOccupancy) {
  SimulationConfig sim;
  sim.duration = 2.0;
  const SimulatedRun run = simulate(sim);
  const LaserMessage& laser = *laser_messages(run).front();
  MapPyramid map(MapPyramidConfig{.levels = 1, .grid = {.resolution = 0.05, .probability_hit = 0.9, .probability_miss = 0.4}});
  map.integrate_scan(laser.scan, laser.odom_pose);
  const std::vector<Eigen::Vector2d> points = usable_end_points(laser.scan, 0.1, 25.0);
  ASSERT_GT(points.size(), 100u);
  const double sigma = 0.3;
  for (const SE2& pose : {laser.odom_pose, laser.odom_pose * SE2(0.037, -0.021, 0.013), laser.odom_pose * SE2(1.0, 0.5, 0.4)}) {
    std::vector<double> r2;
    for (const Eigen::Vector2d& p : points) {
      const double r = 1.0 - interpolate_occupancy(map.level(0), pose * p).value;
      r2.push_back(r * r);
    }
    double all = 0.0;
    double every_third = 0.0;
    std::size_t third = 0;
    for (std::size_t k = 0; k < r2.size(); ++k) {
      all += r2[k];
      if (k % 3 == 0) {
        every_third += r2[k];
        ++third;
      }
    }
    const double expected = -all / (2.0 * sigma * sigma);
    EXPECT_NEAR(log_observation_likelihood(map.level(0), points, pose, sigma), expected, 1e-5 * std::abs(expected));
    const double expected_third = -every_third * static_cast<double>(points.size()) / third / (2.0 * sigma * sigma);
    EXPECT_NEAR(log_observation_likelihood(map.level(0), points, pose, sigma, 3), expected_third,
                1e-5 * std::abs(expected_third));
  }
  // At the scan's pose the end points sit on hits: a much larger likelihood than 0.2 m off.
  EXPECT_GT(log_observation_likelihood(map.level(0), points, laser.odom_pose, sigma),
            log_observation_likelihood(map.level(0), points, laser.odom_pose * SE2(0.2, 0.0, 0.0), sigma) + 10.0);
  EXPECT_THROW(log_observation_likelihood(map.level(0), points, laser.odom_pose, sigma, 0), Error);
}

TEST(RbpfSlam, OneParticleOnANoiselessSimulatorIsScanMatching) {
  SimulationConfig sim;
  sim.duration = 120.0;
  sim.seed = 5;
  sim.laser.range_noise_sigma = 0.0;
  sim.laser.dropout_probability = 0.0;
  sim.odometry.alpha1 = sim.odometry.alpha2 = sim.odometry.alpha3 = sim.odometry.alpha4 = 0.0;
  sim.odometry.scale_error = 0.03;
  sim.odometry.heading_bias = 0.01;
  const SimulatedRun run = simulate(sim);
  const RbpfSlam slam = run_rbpf(run, {.particles = 1});
  EXPECT_EQ(slam.stats().resamplings, 0u);  // N_eff is always 1 = N
  EXPECT_EQ(slam.stats().fallbacks, 0u);    // every scan matched
  const Trajectory trajectory = slam.trajectory();
  ASSERT_EQ(trajectory.size(), run.truth.size());
  const AteResult ate = absolute_trajectory_error(trajectory, run.truth);
  const AteResult odometry = absolute_trajectory_error(test::odometry_of(run), run.truth);
  RecordProperty("ate_rmse_mm", static_cast<int>(1000 * ate.rmse));
  RecordProperty("odometry_ate_rmse_mm", static_cast<int>(1000 * odometry.rmse));
  EXPECT_LT(ate.rmse, 0.08) << "max " << ate.max;
  EXPECT_GT(odometry.rmse, 5.0 * ate.rmse) << odometry.rmse;
  // The path starts at the first odometry pose (the map frame is the odometry frame at t = 0).
  EXPECT_EQ(trajectory[0].pose, laser_messages(run).front()->odom_pose);
}

const SimulatedRun& office_run() { return test::simulated_office(240.0, 7); }

TEST(RbpfSlam, ClosesTheSimulatedOfficeLoopWith30Particles) {
  const SimulatedRun& run = office_run();
  const RbpfSlam slam = run_rbpf(run, {.particles = 30, .seed = 11});
  const Trajectory trajectory = slam.trajectory();
  ASSERT_EQ(trajectory.size(), run.truth.size());
  const AteResult ate = absolute_trajectory_error(trajectory, run.truth);
  const AteResult odometry = absolute_trajectory_error(test::odometry_of(run), run.truth);
  RecordProperty("ate_rmse_mm", static_cast<int>(1000 * ate.rmse));
  RecordProperty("ate_max_mm", static_cast<int>(1000 * ate.max));
  RecordProperty("odometry_ate_rmse_mm", static_cast<int>(1000 * odometry.rmse));
  EXPECT_LT(ate.rmse, 0.05) << "max " << ate.max;
  EXPECT_LT(ate.max, 0.4);
  EXPECT_LT(ate.rmse, 0.2 * odometry.rmse);
  EXPECT_GT(slam.stats().updates, 100u);
  EXPECT_GT(slam.stats().resamplings, 0u);
  EXPECT_LT(slam.stats().resamplings, slam.stats().updates);  // selective: not at every update
  EXPECT_GE(slam.stats().neff_min, 1.0);
}

// The hospital world's south corridor (sim/hospital_world.hpp), driven at 0.4 m/s with a scan
// every 0.2 m: along it the per-scan matching is pulled back to where the map's walls end (they
// end where the last update's beams reached), so the matched motion stayed near zero, the filter
// never reached its next update and its map never grew: the robot stood still for 55 s while it
// drove 22 m (12.6 m ATE over 150 s). The odometry now refutes a matched motion held back over
// four update distances (core/match_progress.hpp) and carries the stretch.
TEST(RbpfSlam, TheOdometryCarriesTheStepWhereTheMatchIsPulledBackAlongACorridor) {
  const SimulatedRun run = simulate(test::hospital_simulation(150.0));
  RbpfConfig config{.particles = 10, .seed = 1};
  config.proposal.matcher.scan_degeneracy_ratio = 0.0;  // the guard alone (core/match_progress.hpp),
  config.scan_odometry_prior_from_motion_noise = false;  // behind the weak prior of constant weight
  const RbpfSlam slam = run_rbpf(run, config);
  const Trajectory trajectory = slam.trajectory();
  ASSERT_EQ(trajectory.size(), run.truth.size());
  const AteResult ate = absolute_trajectory_error(trajectory, run.truth);
  RecordProperty("ate_rmse_mm", static_cast<int>(1000 * ate.rmse));
  EXPECT_LT(ate.rmse, 3.0);  // 1.8 m: each release comes two metres late
  EXPECT_NEAR(trajectory.path_length(), run.truth.path_length(), 0.1 * run.truth.path_length());
  EXPECT_GT(slam.stats().stuck_matches, 0u);
  EXPECT_GT(slam.stats().updates, 60u);  // 60 m driven (30 particles before: no update after t = 45 s)
}

// The same run with the defaults: along the plain corridor the scan's open translation is the
// prediction's (HectorMatcherConfig::scan_degeneracy_ratio), so the matches are not pinned to the
// last update's viewpoint in the first place.
TEST(RbpfSlam, AlongAPlainCorridorTheMatchIsNotPinnedToTheLastUpdatesViewpoint) {
  const SimulatedRun run = simulate(test::hospital_simulation(150.0));
  const RbpfSlam slam = run_rbpf(run, {.particles = 10, .seed = 1});
  const Trajectory trajectory = slam.trajectory();
  const AteResult ate = absolute_trajectory_error(trajectory, run.truth);
  RecordProperty("ate_rmse_mm", static_cast<int>(1000 * ate.rmse));
  RecordProperty("path_length_m", static_cast<int>(trajectory.path_length()));
  // 0.21 m (0.43 m before the learnt prior and the open axis kept in updates; the guard alone 1.8 m)
  EXPECT_LT(ate.rmse, 0.8);
  EXPECT_NEAR(trajectory.path_length(), run.truth.path_length(), 0.03 * run.truth.path_length());
}

// The hospital world over one lap and a half (600 s, 240 m, its loop closed at 525 s), every
// default: the per-scan matching holds the odometry by the odometry's own learnt noise
// (RbpfConfig::scan_odometry_prior_from_motion_noise), and along the corridor's open axis an
// update keeps the prediction: no start noise, no fit of the map's pull
// (Proposal.AlongACorridorsOpenAxisTheMeanIsThePredictions).
// Over 10 s windows the filter stays near the odometry it was given; with the weak prior of
// constant weight the matches slid and were held back by metres near the corridor's recesses.
// Since its maps hold a grazing wall as a wall, not as dots a beam apart (grid.surface_hit_weight),
// nothing pins a match to the last update's viewpoint and it beats the odometry.
TEST(RbpfSlam, OverTenSecondsTheHospitalWorldStaysNearItsOdometry) {
  const SimulatedRun run = simulate(test::hospital_simulation(600.0));
  const RpeConfig ten_seconds{.window = RpeWindow::kTime, .delta = 10.0};
  const double odometry = relative_pose_error(test::odometry_of(run), run.truth, ten_seconds).translation.mean;
  const auto error = [&](const RbpfConfig& config) {
    return relative_pose_error(run_rbpf(run, config).trajectory(), run.truth, ten_seconds).translation.mean;
  };
  RbpfConfig dots;
  dots.map.grid.surface_hit_weight = 0.0;
  RbpfConfig constant = dots;
  constant.scan_odometry_prior_from_motion_noise = false;
  const double walls = error(RbpfConfig{});
  const double learnt = error(dots);
  const double weak = error(constant);
  RecordProperty("odometry_mm", static_cast<int>(1000 * odometry));
  RecordProperty("walls_mm", static_cast<int>(1000 * walls));
  RecordProperty("learnt_mm", static_cast<int>(1000 * learnt));
  RecordProperty("constant_mm", static_cast<int>(1000 * weak));
  // Measured, with the walls' dots: 0.038 m, 0.104 m with the constant prior; the odometry 0.029 m
  // (the filter's own poses, before `slam2d map` smooths them with the odometry). Before: 0.054 m
  // with the learnt prior and the fit reading the map along the open axis, 0.161 m with neither.
  // With the walls: 0.021 m.
  EXPECT_LT(walls, odometry);
  EXPECT_LT(walls, learnt);
  EXPECT_LT(learnt, 1.6 * odometry);
  EXPECT_GT(weak, 2.5 * odometry) << "the world no longer tests the prior";
}

// The hospital world with the held-out hospital log's mixed pixels (700 s): phantoms hang ahead of
// the robot where a corridor's wall leaves the beams' reach, and the scans say little about the
// distance driven. With GMapping's fixed motion noise (srr 0.1: 5 cm along each 0.5 m update) the
// particles took that distance from the scans, stuck along the corridors and caught up; with the
// noise along the travel from the odometry's learnt model (RbpfConfig::motion_along_from_learnt_noise)
// they take it from the wheels, and beat them over 10 s windows.
TEST(RbpfSlam, TheDistanceDrivenComesFromTheOdometrysLearntNoiseInTheHospitalWorldWithPhantoms) {
  SimulatedRun run = simulate(test::hospital_simulation(700.0));
  apply_faults({parse_fault("mixed-pixels:p=1,alternate=6")}, run.messages, 1);
  const RpeConfig ten_seconds{.window = RpeWindow::kTime, .delta = 10.0};
  const double odometry = relative_pose_error(test::odometry_of(run), run.truth, ten_seconds).translation.mean;
  const auto error = [&](const RbpfConfig& config) {
    return relative_pose_error(run_rbpf(run, config).trajectory(), run.truth, ten_seconds).translation.mean;
  };
  RbpfConfig fixed;
  fixed.motion_along_from_learnt_noise = false;
  const double learnt = error(RbpfConfig{});
  const double fixed_noise = error(fixed);
  RecordProperty("odometry_mm", static_cast<int>(1000 * odometry));
  RecordProperty("learnt_mm", static_cast<int>(1000 * learnt));
  RecordProperty("fixed_mm", static_cast<int>(1000 * fixed_noise));
  // Measured: 0.018 m, 0.025 with the fixed noise, the odometry 0.030.
  EXPECT_LT(learnt, odometry);
  EXPECT_LT(learnt, 0.8 * fixed_noise);
}

TEST(RbpfSlam, SameSeedSameResultOtherSeedOtherResult) {
  SimulationConfig sim;
  sim.duration = 60.0;
  const SimulatedRun run = simulate(sim);
  const RbpfConfig config{.particles = 8, .seed = 42};
  const Trajectory a = run_rbpf(run, config).trajectory();
  const Trajectory b = run_rbpf(run, config).trajectory();
  RbpfConfig other = config;
  other.seed = 43;
  const Trajectory c = run_rbpf(run, other).trajectory();
  ASSERT_EQ(a.size(), b.size());
  bool differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].pose, b[i].pose) << "scan " << i;
    differs = differs || !(a[i].pose == c[i].pose);
  }
  EXPECT_TRUE(differs);
}

TEST(RbpfSlam, TrajectoryPassesThroughTheUpdatePosesAndSpreadsEachCorrection) {
  SimulationConfig sim;
  sim.duration = 60.0;
  const SimulatedRun run = simulate(sim);
  // One particle: the pose add_scan reports is the forward chain of the final path (its pose at
  // the last update composed with the odometry since).
  RbpfSlam slam({.particles = 1});
  std::vector<std::size_t> update_scans;
  std::vector<SE2> forward;
  for (const LaserMessage* laser : laser_messages(run)) {
    const RbpfStep step = slam.add_scan(laser->scan, laser->odom_pose);
    if (step.updated) update_scans.push_back(forward.size());
    forward.push_back(step.T_map_robot);
  }
  std::vector<SE2> path(update_scans.size());
  for (const RbpfPathNode* node = slam.best().path.get(); node != nullptr; node = node->parent.get()) {
    path[node->update] = node->T_map_robot;
  }
  const Trajectory trajectory = slam.trajectory();
  ASSERT_EQ(trajectory.size(), forward.size());
  ASSERT_GT(update_scans.size(), 10u);
  for (std::size_t k = 0; k < update_scans.size(); ++k) {
    EXPECT_EQ(trajectory[update_scans[k]].pose, path[k]) << "update " << k;
  }
  // After the last update nothing is known ahead: the forward chain.
  for (std::size_t i = update_scans.back(); i < forward.size(); ++i) EXPECT_EQ(trajectory[i].pose, forward[i]);
  // Before it, the scans between two updates move off the forward chain towards the next update.
  double largest_shift = 0.0;
  for (std::size_t i = 0; i < update_scans.back(); ++i) {
    largest_shift = std::max(largest_shift, (trajectory[i].pose.translation() - forward[i].translation()).norm());
  }
  RecordProperty("largest_shift_mm", static_cast<int>(1000 * largest_shift));
  EXPECT_GT(largest_shift, 1e-3);
  EXPECT_LT(largest_shift, 0.2);
}

// The path keeps the proposal's mean at each update; the particle moves to a draw around it. The
// draw's noise (Sigma) shows in the motion between two updates: against the truth's, the path's
// motions are closer than the draws' (a path of the drawn poses fails it).
TEST(RbpfSlam, ThePathHoldsTheProposalMeanNotTheDraw) {
  SimulationConfig sim;
  sim.duration = 120.0;
  sim.seed = 3;
  const SimulatedRun run = simulate(sim);
  RbpfSlam slam({.particles = 1, .seed = 5});
  std::vector<std::size_t> update_scans;
  std::vector<SE2> drawn;
  std::size_t scan = 0;
  for (const LaserMessage* laser : laser_messages(run)) {
    if (slam.add_scan(laser->scan, laser->odom_pose).updated) {
      update_scans.push_back(scan);
      drawn.push_back(slam.particles()[0].T_map_robot);
    }
    ++scan;
  }
  std::vector<SE2> path(update_scans.size());
  for (const RbpfPathNode* node = slam.best().path.get(); node != nullptr; node = node->parent.get()) {
    path[node->update] = node->T_map_robot;
  }
  ASSERT_GT(update_scans.size(), 50u);
  double path_error = 0.0;
  double drawn_error = 0.0;
  for (std::size_t k = 1; k < update_scans.size(); ++k) {
    const SE2 truth = run.truth[update_scans[k - 1]].pose.between(run.truth[update_scans[k]].pose);
    path_error += truth.between(path[k - 1].between(path[k])).translation().squaredNorm();
    drawn_error += truth.between(drawn[k - 1].between(drawn[k])).translation().squaredNorm();
  }
  const double n = static_cast<double>(update_scans.size() - 1);
  path_error = std::sqrt(path_error / n);
  drawn_error = std::sqrt(drawn_error / n);
  RecordProperty("path_rms_mm", static_cast<int>(1e3 * path_error));
  RecordProperty("drawn_rms_mm", static_cast<int>(1e3 * drawn_error));
  EXPECT_LT(path_error, 0.95 * drawn_error) << path_error << " " << drawn_error;  // 0.88 here; sim seeds 1-6: 0.88-0.97 (seed 4 loses the one particle)
}

TEST(RbpfSlam, ParticlesShareMapTilesUntilTheyWrite) {
  SimulationConfig sim;
  sim.duration = 10.0;
  const SimulatedRun run = simulate(sim);
  const auto lasers = laser_messages(run);
  RbpfConfig config;
  config.particles = 4;
  config.resample_threshold = 0.0;  // never resample: every particle keeps its own line of maps
  RbpfSlam slam(config);
  slam.add_scan(lasers.front()->scan, lasers.front()->odom_pose);
  const OccupancyGrid& first = slam.particles()[0].map.level(0);
  const CellIndex cell = first.geometry().cell_of(lasers.front()->odom_pose.translation());
  for (const RbpfParticle& particle : slam.particles()) {
    EXPECT_TRUE(particle.map.level(0).cells().shares_tile_with(first.cells(), cell));  // one copy of the first scan
  }
  for (const LaserMessage* laser : lasers) slam.add_scan(laser->scan, laser->odom_pose);
  ASSERT_GT(slam.stats().updates, 2u);
  ASSERT_EQ(slam.stats().resamplings, 0u);
  // After updates at different poses each particle owns the tiles it wrote.
  const OccupancyGrid& a = slam.particles()[0].map.level(0);
  const OccupancyGrid& b = slam.particles()[1].map.level(0);
  EXPECT_FALSE(a.cells().shares_tile_with(b.cells(), cell));
}

TEST(RbpfSlam, ReleasesALongPathWithoutDeepRecursion) {
  auto node = std::make_shared<RbpfPathNode>(SE2(), 0, nullptr);
  for (std::size_t i = 1; i < 1'000'000; ++i) node = std::make_shared<RbpfPathNode>(SE2(), i, std::move(node));
  node.reset();  // would overflow the stack with a recursive destructor
  SUCCEED();
}

// 30 s of scans missing, over an odometry that turns 0.05 rad a metre too little: crossing the gap
// as one long step, the first scan after it matches a wrong place (ATE > 0.5 m); the filter waits,
// maps the scans after the gap anew and finds them in the best particle's map (ATE < 0.1 m). The true
// poses as the odometry: its drift measured before the gap is within the per-scan matching's
// reach, and the gap is crossed as before.
TEST(RbpfSlam, FindsItsPlaceInTheOldMapAfterAGap) {
  const SimulatedRun& run = test::simulated_office(150.0, 4);
  const std::vector<const LaserMessage*> lasers = laser_messages(run);
  const std::vector<SE2> drifting = test::odometry_with_heading_drift(run, 0.05);
  const auto map_across_gap = [&](bool relocalize, bool exact = false) {
    RbpfConfig config;
    config.particles = 10;
    config.relocalization.enabled = relocalize;
    RbpfSlam slam(config);
    Trajectory truth;
    for (std::size_t i = 0; i < lasers.size(); ++i) {
      if (lasers[i]->scan.stamp >= 100.0 && lasers[i]->scan.stamp < 130.0) continue;
      slam.add_scan(lasers[i]->scan, exact ? run.truth[i].pose : drifting[i]);
      truth.push_back(lasers[i]->scan.stamp, run.truth[i].pose);
    }
    EXPECT_EQ(slam.trajectory().size(), truth.size());
    return std::pair{slam.gap_stats(), absolute_trajectory_error(slam.trajectory(), truth).rmse};
  };
  const auto [stats, rmse] = map_across_gap(true);
  const auto [without_stats, without] = map_across_gap(false);
  const auto [exact_stats, exact] = map_across_gap(true, true);
  EXPECT_EQ(stats.gaps, 1u);
  EXPECT_EQ(stats.relocalized, 1u);
  EXPECT_LT(rmse, 0.1);
  EXPECT_EQ(without_stats.gaps, 0u);
  EXPECT_GT(without, 0.5);
  EXPECT_EQ(exact_stats.tracked, 1u);
  EXPECT_EQ(exact_stats.relocalized, 0u);
  EXPECT_LT(exact, 0.05);
}

// While the filter searches (here never confirmed, nor a match taken alone), the scans since the
// gap are in the trajectory at their poses in the new map, and the written map holds the best
// particle's map beneath the new one.
TEST(RbpfSlam, WritesTheScansSinceAGapItHasNotPlacedInTheTrajectoryAndTheMap) {
  const SimulatedRun& run = test::simulated_office(150.0, 4);
  RbpfConfig config;
  config.particles = 5;
  config.relocalization.gap.track_translation = config.relocalization.gap.track_rotation = 0.0;
  config.relocalization.confirm_min_distance = config.relocalization.confirm_max_distance = 1e6;
  RbpfSlam slam(config);
  std::size_t added = 0;
  for (const LaserMessage* laser : laser_messages(run)) {
    if (laser->scan.stamp >= 100.0 && laser->scan.stamp < 130.0) continue;
    slam.add_scan(laser->scan, laser->odom_pose);
    ++added;
  }
  EXPECT_EQ(slam.gap_stats().gaps, 1u);
  EXPECT_EQ(slam.gap_stats().relocalized, 0u);
  EXPECT_EQ(slam.trajectory().size(), added);
  const auto known = [](const OccupancyMap& map) {
    return std::count_if(map.cells.begin(), map.cells.end(), [](std::int8_t c) { return c != OccupancyMap::kUnknown; });
  };
  EXPECT_GT(known(slam.occupancy_map()), known(slam.map().to_occupancy_map()));
}

TEST(RbpfSlam, RejectsBadConfiguration) {
  EXPECT_THROW(RbpfSlam({.particles = 0}), Error);
  EXPECT_THROW(RbpfSlam({.max_range = 0.0}), Error);
  EXPECT_THROW(RbpfSlam({.resample_threshold = 1.5}), Error);
  RbpfConfig config;
  config.proposal.likelihood_sigma = 0.0;
  EXPECT_THROW(RbpfSlam{config}, Error);
  config = {};
  config.motion.min_sigma_rotation = 0.0;
  EXPECT_THROW(RbpfSlam{config}, Error);
  config = {};
  config.motion.max_sigma_translation = 0.5 * config.motion.min_sigma_translation;  // a cap under its floor
  EXPECT_THROW(RbpfSlam{config}, Error);
  config = {};
  config.proposal.likelihood_stride = 0;
  EXPECT_THROW(RbpfSlam{config}, Error);
  config = {};
  config.start_noise = -0.1;
  EXPECT_THROW(RbpfSlam{config}, Error);
  config = {};
  config.scan_odometry_rotation_search = -0.1;
  EXPECT_THROW(RbpfSlam{config}, Error);
  config = {};
  config.scan_odometry_rotation_margin = 1.0;
  EXPECT_THROW(RbpfSlam{config}, Error);
  config = {};
  config.scan_odometry_rotation_step = 0.0;
  EXPECT_THROW(RbpfSlam{config}, Error);
}

}  // namespace
}  // namespace slam2d
