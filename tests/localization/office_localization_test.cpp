// SPDX-License-Identifier: BSD-3-Clause
// Every localization method in the simulated office (the ground-truth map of its walls): tracking
// from a known start, global localization (MCL, Markov, hybrid), recovery after a kidnap (MCL),
// and the EKF reporting itself lost instead of drifting after one.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/hybrid.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/localization/session.hpp"
#include "slam2d/sim/fault_injection.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/sim/world.hpp"
#include "support/simulated_office.hpp"
#include "localization/localization_run.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

const SimulatedRun& office_run() { return test::simulated_office(120.0, 5); }

const LocalizationMap& office_map() {
  static const LocalizationMap map(rasterize_world(make_world("office"), 0.05));
  return map;
}

using RunResult = test::LocalizationRun;

RunResult run(Localizer& localizer, std::optional<Kidnap> kidnap = std::nullopt) {
  return test::run_localization(localizer, office_run(), kidnap);
}

// Mean and max error over the scans from `from` s on.
std::pair<double, double> error_after(const RunResult& result, double from) {
  const double rate = 10.0;  // the simulator's laser rate
  double sum = 0.0;
  double worst = 0.0;
  std::size_t n = 0;
  for (std::size_t i = static_cast<std::size_t>(from * rate); i < result.errors.size(); ++i) {
    sum += result.errors[i];
    worst = std::max(worst, result.errors[i]);
    ++n;
  }
  return {n > 0 ? sum / n : 0.0, worst};
}

SE2 start_pose() { return office_run().truth[0].pose; }
Covariance3 start_covariance() { return covariance_from_sigmas(0.2, 0.2, 0.1); }
SE2 start_guess() { return start_pose() * SE2(0.15, -0.1, 0.05); }

TEST(OfficeLocalization, MclTracksFromAKnownStart) {
  MonteCarloLocalization mcl(office_map(), MclConfig{.max_particles = 2000, .seed = 2});
  mcl.initialize(start_guess(), start_covariance());
  const RunResult result = run(mcl);
  const auto [mean, worst] = error_after(result, 2.0);
  EXPECT_LT(mean, 0.08);
  EXPECT_LT(worst, 0.3);
  EXPECT_EQ(result.summary.lost_events, 0u);
  ASSERT_TRUE(result.summary.converged_at_s.has_value());
  EXPECT_LT(*result.summary.converged_at_s, 2.0);
}

TEST(OfficeLocalization, EkfTracksFromAKnownStart) {
  EkfLocalization ekf(office_map());
  ekf.initialize(start_guess(), start_covariance());
  const RunResult result = run(ekf);
  const auto [mean, worst] = error_after(result, 1.0);
  EXPECT_LT(mean, 0.05);
  EXPECT_LT(worst, 0.2);
  EXPECT_EQ(result.summary.lost_events, 0u);
  EXPECT_GT(ekf.stats().accepted, ekf.stats().updates * 9 / 10);
  // Honest covariance: the error stays within a few sigmas.
  EXPECT_LT(std::sqrt(ekf.covariance()(0, 0)), 0.1);
}

// The office run with its odometry given a random walk (perturb's odom-noise) `level` times the
// localization benchmark's 1x (bench/datasets/localize_benchmark.py).
SimulatedRun noisy_odometry_run(double level) {
  SimulatedRun run = office_run();
  const std::string spec = "odom-noise:translation=" + std::to_string(0.1 * level) +
                           ",heading=" + std::to_string(0.04 * level) + ",rotation=" + std::to_string(0.1 * level);
  apply_faults({parse_fault(spec)}, run.messages, 3);
  return run;
}

// Odometry worse than the EKF's motion model: with the model fixed the filter trusts its
// prediction too much, its search window stays narrow and it falls behind; with the noise learnt
// from its matches it keeps tracking (issue 40: each measurement weighed by its own uncertainty).
TEST(OfficeLocalization, EkfLearnsAnOdometryWorseThanItsModel) {
  const SimulatedRun noisy = noisy_odometry_run(4.0);
  const auto mean_error = [&](const EkfConfig& config, double* translation_scale) {
    EkfLocalization ekf(office_map(), config);
    ekf.initialize(start_guess(), start_covariance());
    const RunResult result = test::run_localization(ekf, noisy);
    if (translation_scale != nullptr) *translation_scale = ekf.motion_noise()->translation_scale();
    double sum = 0.0;
    for (std::size_t i = 10; i < result.errors.size(); ++i) sum += result.errors[i];
    return sum / static_cast<double>(result.errors.size() - 10);
  };
  EkfConfig fixed;
  fixed.motion_noise.window = 0.0;
  double scale = 0.0;
  const double learnt_error = mean_error(EkfConfig{}, &scale);
  const double fixed_error = mean_error(fixed, nullptr);
  EXPECT_GT(scale, 1.5);
  EXPECT_LT(learnt_error, 0.06);
  EXPECT_LT(learnt_error, 0.7 * fixed_error);
}

TEST(OfficeLocalization, MarkovGridTracksFromAKnownStart) {
  MarkovGridLocalization markov(office_map());
  markov.initialize(start_guess(), start_covariance());
  const RunResult result = run(markov);
  const auto [mean, worst] = error_after(result, 3.0);
  EXPECT_LT(mean, 0.2);
  EXPECT_LT(worst, 0.6);
  EXPECT_EQ(result.summary.lost_events, 0u);
}

TEST(OfficeLocalization, HybridTracksFromAKnownStart) {
  HybridLocalization hybrid(office_map());
  hybrid.initialize(start_guess(), start_covariance());
  const RunResult result = run(hybrid);
  const auto [mean, worst] = error_after(result, 1.0);
  EXPECT_LT(mean, 0.05);
  EXPECT_LT(worst, 0.3);
  EXPECT_TRUE(hybrid.ekf_active());
}

// After convergence from a uniform prior, every localized step is near the truth.
void expect_global_localization(const RunResult& result, double max_converge_s) {
  ASSERT_TRUE(result.summary.converged_at_s.has_value());
  EXPECT_LT(*result.summary.converged_at_s, max_converge_s);
  const auto [mean, worst] = error_after(result, *result.summary.converged_at_s + 5.0);
  EXPECT_LT(mean, 0.15);
  EXPECT_LT(worst, 0.6);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < result.errors.size(); ++i) wrong += result.localized[i] && result.errors[i] > 1.0 ? 1 : 0;
  EXPECT_LE(wrong, 5u) << "steps reported localized more than 1 m from the truth";
}

TEST(OfficeLocalization, MclLocalizesGlobally) {
  MonteCarloLocalization mcl(office_map(), MclConfig{.seed = 3});  // default settings
  mcl.initialize_global();
  const RunResult result = run(mcl);
  expect_global_localization(result, 30.0);
  EXPECT_LT(mcl.particles().size(), 2000u) << "KLD-sampling shrinks the set once localized";
}

TEST(OfficeLocalization, MarkovGridLocalizesGlobally) {
  MarkovGridLocalization markov(office_map());
  markov.initialize_global();
  const RunResult result = run(markov);
  expect_global_localization(result, 30.0);
  EXPECT_LT(markov.evaluated_last(), markov.active_cells() + 1);
}

TEST(OfficeLocalization, HybridLocalizesGlobally) {
  HybridLocalization hybrid(office_map());
  hybrid.initialize_global();
  const RunResult result = run(hybrid);
  expect_global_localization(result, 40.0);
  EXPECT_GE(hybrid.handovers(), 1u);
}

TEST(OfficeLocalization, MclRecoversAfterAKidnap) {
  MonteCarloLocalization mcl(office_map(), MclConfig{.max_particles = 10000, .seed = 4});
  mcl.initialize(start_guess(), start_covariance());
  const Kidnap kidnap{.at = 40.0, .by = SE2(5.0, 0.0, std::numbers::pi / 2)};
  const RunResult result = run(mcl, kidnap);
  EXPECT_GT(error_after(result, 40.5).second, 2.0) << "the kidnap moved the estimate";
  EXPECT_GE(result.summary.lost_events, 1u);
  ASSERT_TRUE(result.summary.recovered_after_s.has_value());
  const double back = 40.0 + *result.summary.recovered_after_s;
  const auto [mean, worst] = error_after(result, back + 5.0);
  EXPECT_LT(mean, 0.15);
  EXPECT_LT(worst, 0.6);
}

TEST(OfficeLocalization, EkfReportsLostAfterAKidnapInsteadOfDrifting) {
  EkfLocalization ekf(office_map());
  ekf.initialize(start_guess(), start_covariance());
  const Kidnap kidnap{.at = 40.0, .by = SE2(5.0, 0.0, std::numbers::pi / 2)};
  const RunResult result = run(ekf, kidnap);
  EXPECT_GE(result.summary.lost_events, 1u);
  EXPECT_TRUE(ekf.lost());
  // Within 2 s of the kidnap it says so, and it never claims a wrong pose after that.
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < result.errors.size(); ++i) {
    if (office_run().truth[i].stamp > kidnap.at + 2.0) wrong += result.localized[i] && result.errors[i] > 1.0 ? 1 : 0;
  }
  EXPECT_EQ(wrong, 0u) << "scans reported localized more than 1 m from the truth";
}

TEST(OfficeLocalization, EkfHasNoGlobalModeButMclNeedsAnInitialisation) {
  MonteCarloLocalization mcl(office_map());
  EXPECT_THROW(mcl.update(SE2(), laser_messages(office_run())[0]->scan), Error);
  EkfLocalization ekf(office_map());
  EXPECT_THROW(ekf.update(SE2(), laser_messages(office_run())[0]->scan), Error);
}

}  // namespace
}  // namespace slam2d
