// SPDX-License-Identifier: BSD-3-Clause
// A method's per-scan poses smoothed with the odometry (slam/fusion/odometry_smoothing): against a
// known path, the two streams' noises are recovered, a jittery method is brought below both its
// own and the odometry's error on short relations, a sure method is left where it is, and an
// odometry jump is cut from the chain instead of being spread over the poses; a localizer's run is
// smoothed where it was localized only.

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/slam/fusion/odometry_smoothing.hpp"

namespace slam2d {
namespace {

// 10 Hz, 300 s: 0.5 m/s along curves that change every 10 s, with stops and turns in place.
std::vector<SE2> drive() {
  std::vector<SE2> path;
  SE2 pose;
  path.push_back(pose);
  for (int i = 1; i < 3000; ++i) {
    const int phase = (i / 100) % 6;
    const double turn = phase == 0 ? 0.02 : phase == 1 ? -0.015 : phase == 2 ? 0.0 : phase == 3 ? 0.01 : 0.0;
    SE2 step(0.05, 0.0, turn);
    if (phase == 4) step = SE2(0.0, 0.0, 0.05);  // a turn in place
    if (phase == 5 && i % 100 < 30) step = SE2();  // standing
    pose = pose * step;
    path.push_back(pose);
  }
  return path;
}

// Each pose moved by white noise in its own frame.
std::vector<SE2> jittered(const std::vector<SE2>& path, double sigma_xy, double sigma_theta, Rng& rng) {
  std::vector<SE2> out;
  for (const SE2& pose : path) out.push_back(pose * SE2(rng.gaussian(0, sigma_xy), rng.gaussian(0, sigma_xy), rng.gaussian(0, sigma_theta)));
  return out;
}

// Odometry: the path's increments, each with noise growing with its length and turn (a random walk).
std::vector<SE2> odometry_of(const std::vector<SE2>& path, double per_metre, double per_radian, Rng& rng) {
  std::vector<SE2> out{path.front()};
  for (std::size_t i = 1; i < path.size(); ++i) {
    const SE2 u = path[i - 1].between(path[i]);
    const double d = u.translation().norm();
    const double a = std::abs(u.theta());
    const double st = per_metre * d + 0.2 * per_radian * a + 1e-4;
    const double sr = per_metre * d + per_radian * a + 1e-4;
    out.push_back(out.back() * u * SE2(rng.gaussian(0, st), rng.gaussian(0, st), rng.gaussian(0, sr)));
  }
  return out;
}

// Mean translational error of the relations i -> i + span against the path's (Kuemmerle's).
double relation_error(const std::vector<SE2>& estimate, const std::vector<SE2>& truth, std::size_t span) {
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i + span < truth.size(); i += 5) {
    const SE2 e = truth[i].between(truth[i + span]).between(estimate[i].between(estimate[i + span]));
    sum += e.translation().norm();
    ++count;
  }
  return sum / static_cast<double>(count);
}

TEST(OdometrySmoothing, RecoversTheJitterOfEachStream) {
  Rng rng(7);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = jittered(truth, 0.02, 0.015, rng);
  const std::vector<SE2> odometry = odometry_of(truth, 0.02, 0.02, rng);
  const PoseStreamNoise noise = estimate_pose_stream_noise(method, odometry);
  for (int axis = 0; axis < 2; ++axis) EXPECT_NEAR(noise.method_jitter[axis], 0.02, 0.004) << axis;
  EXPECT_NEAR(noise.method_jitter[2], 0.015, 0.003);
  // The odometry has no white noise of its own: its random walk shows in the drift's scale only.
  EXPECT_LT(noise.odometry_jitter.maxCoeff(), 0.005);
}

TEST(OdometrySmoothing, AJitteryMethodBecomesBetterThanBothOnShortRelations) {
  Rng rng(11);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = jittered(truth, 0.02, 0.015, rng);
  const std::vector<SE2> odometry = odometry_of(truth, 0.02, 0.02, rng);
  OdometrySmoothingStats stats;
  const std::vector<SE2> smoothed = smooth_with_odometry(method, odometry, {}, &stats);
  ASSERT_TRUE(stats.applied);
  EXPECT_EQ(stats.poses, truth.size());
  EXPECT_LT(stats.steps_refused, 10u);
  for (const std::size_t span : {10u, 100u}) {  // 1 s and 10 s
    const double m = relation_error(method, truth, span);
    const double o = relation_error(odometry, truth, span);
    const double s = relation_error(smoothed, truth, span);
    EXPECT_LT(s, 0.6 * m) << span << ": method " << m << " odometry " << o << " smoothed " << s;
    // The odometry is the better stream over 1 s here (a few mm): the fused relations come within
    // the noise of the estimated covariances of it (the exact product would reach it).
    EXPECT_LE(s, 1.25 * o) << span << ": method " << m << " odometry " << o << " smoothed " << s;
  }
  // Over the whole run the method's (bounded) error holds the drift of the odometry: the smoothed
  // poses stay near the path.
  double worst = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) worst = std::max(worst, (smoothed[i].translation() - truth[i].translation()).norm());
  EXPECT_LT(worst, 0.1);
}

TEST(OdometrySmoothing, ASureMethodIsLeftWhereItIs) {
  Rng rng(3);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = jittered(truth, 0.001, 0.0005, rng);  // a good scan matcher
  const std::vector<SE2> odometry = jittered(odometry_of(truth, 0.05, 0.05, rng), 0.01, 0.01, rng);
  OdometrySmoothingStats stats;
  const std::vector<SE2> smoothed = smooth_with_odometry(method, odometry, {}, &stats);
  ASSERT_TRUE(stats.applied);
  EXPECT_LT(stats.max_change_m, 0.003);
  EXPECT_LE(relation_error(smoothed, truth, 10), 1.05 * relation_error(method, truth, 10));
}

TEST(OdometrySmoothing, AnOdometryJumpIsCutNotSpread) {
  Rng rng(5);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = jittered(truth, 0.01, 0.005, rng);
  std::vector<SE2> odometry = odometry_of(truth, 0.02, 0.02, rng);
  for (std::size_t i = 1500; i < odometry.size(); ++i) odometry[i] = SE2(1.0, 0.0, 0.3) * odometry[i];  // a 1 m jump
  OdometrySmoothingStats stats;
  const std::vector<SE2> smoothed = smooth_with_odometry(method, odometry, {}, &stats);
  ASSERT_TRUE(stats.applied);
  EXPECT_GE(stats.steps_refused, 1u);
  double worst = 0.0;
  for (std::size_t i = 1400; i < 1600; ++i) worst = std::max(worst, (smoothed[i].translation() - truth[i].translation()).norm());
  EXPECT_LT(worst, 0.05);
}

// A method whose error is slow (a tracker following its own local map): a Gauss-Markov error of
// time constant `tau` scans and spread `sigma` in the map frame, plus its jitter.
std::vector<SE2> slowly_wrong(const std::vector<SE2>& path, double sigma, double tau, Rng& rng) {
  const double phi = std::exp(-1.0 / tau);
  const double step = sigma * std::sqrt(1.0 - phi * phi);
  Eigen::Vector2d b(rng.gaussian(0, sigma), rng.gaussian(0, sigma));
  std::vector<SE2> out;
  for (const SE2& pose : path) {
    b = phi * b + Eigen::Vector2d(rng.gaussian(0, step), rng.gaussian(0, step));
    out.push_back(SE2(b.x(), b.y(), 0.0) * pose * SE2(rng.gaussian(0, 0.003), rng.gaussian(0, 0.003), rng.gaussian(0, 0.002)));
  }
  return out;
}

// The method's poses smoothed with two streams and with the scan odometry as the third (stats of
// the latter).
struct SmoothedBothWays {
  std::vector<SE2> two, three;
  OdometrySmoothingStats stats;
};

SmoothedBothWays smooth_both_ways(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                  const std::vector<SE2>& scan) {
  SmoothedBothWays out;
  out.two = smooth_with_odometry(method, odometry);
  out.three = smooth_with_odometry(method, odometry, {}, &out.stats, &scan);
  return out;
}

// Two streams cannot tell the method's slow error from the odometry's drift and count it as the
// odometry's; a third (scan odometry, its own random walk) tells them apart, and the smoother
// then lets the odometry carry the seconds over which the method is slowly wrong.
TEST(OdometrySmoothing, AThirdStreamTellsTheMethodsSlowErrorFromTheOdometrysDrift) {
  Rng rng(13);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = slowly_wrong(truth, 0.03, 30.0, rng);
  const std::vector<SE2> odometry = odometry_of(truth, 0.01, 0.01, rng);
  const std::vector<SE2> scan = odometry_of(truth, 0.03, 0.03, rng);
  const PoseStreamNoise two = estimate_pose_stream_noise(method, odometry);
  const PoseStreamNoise three = estimate_pose_stream_noise(method, odometry, {}, &scan);
  EXPECT_EQ(two.streams, 2u);
  EXPECT_EQ(three.streams, 3u);
  EXPECT_EQ(two.method_slow, Eigen::Vector3d::Zero());
  EXPECT_NEAR(three.method_slow.x(), 0.03, 0.012);  // 0.0225 m, time constant 16 scans (truth 30)
  EXPECT_GE(three.method_time_constant.x(), 8.0);
  EXPECT_LE(three.method_time_constant.x(), 16.0);
  EXPECT_GT(two.translation_scale, 3.0 * three.translation_scale);  // the slow error counted as drift
  const SmoothedBothWays smoothed = smooth_both_ways(method, odometry, scan);
  ASSERT_TRUE(smoothed.stats.applied);
  for (const std::size_t span : {10u, 100u}) {
    const double m = relation_error(method, truth, span);
    const double o = relation_error(odometry, truth, span);
    const double s2 = relation_error(smoothed.two, truth, span);
    const double s3 = relation_error(smoothed.three, truth, span);
    // Two streams leave the method's error as it was (0.027 m at 1 s, 0.054 at 10 s); three come
    // near the odometry's (0.0030 against 0.0020 m at 1 s, where its noise, 0.6 mm a step, is below
    // what the motion model's floor lets the smoother believe; 0.0167 against 0.0152 m at 10 s).
    EXPECT_LT(s3, 0.5 * s2) << span << ": method " << m << " odometry " << o << " two " << s2 << " three " << s3;
    EXPECT_LT(s3, (span == 10 ? 1.6 : 1.2) * o) << span << ": method " << m << " odometry " << o << " two " << s2
                                                 << " three " << s3;
  }
}

// The smoother keeps every checkpoint_interval-th filtered state and filters each stretch again on
// its way back: any interval gives the poses of the plain smoother that keeps every state (1), to
// the bit, across stretch boundaries, a jump cut from the chain and the slow error's states.
TEST(OdometrySmoothing, CheckpointsGiveThePlainSmoothersPoses) {
  Rng rng(17);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = slowly_wrong(truth, 0.03, 30.0, rng);
  const std::vector<SE2> odometry = odometry_of(truth, 0.01, 0.01, rng);
  std::vector<SE2> jumping = odometry;
  for (std::size_t i = 1100; i < jumping.size(); ++i) jumping[i] = SE2(1.0, 0.0, 0.3) * jumping[i];  // a 1 m jump
  const std::vector<SE2> scan = odometry_of(truth, 0.03, 0.03, rng);
  // The slow error's states (three streams), and a jump cut from the chain (two).
  for (const bool third : {true, false}) {
    const std::vector<SE2>& odo = third ? odometry : jumping;
    const std::vector<SE2>* stream = third ? &scan : nullptr;
    OdometrySmoothingConfig plain;
    plain.checkpoint_interval = 1;
    OdometrySmoothingStats plain_stats;
    const std::vector<SE2> expected = smooth_with_odometry(method, odo, plain, &plain_stats, stream);
    ASSERT_TRUE(plain_stats.applied);
    ASSERT_NE(expected, method);
    if (third) {
      ASSERT_GT(plain_stats.noise.method_slow.x(), 0.0);
    } else {
      ASSERT_GE(plain_stats.steps_refused, 1u);
    }
    for (const std::size_t interval : {std::size_t{7}, std::size_t{1024}, truth.size() - 1, truth.size(), std::size_t{100000}}) {
      OdometrySmoothingConfig config;
      config.checkpoint_interval = interval;
      OdometrySmoothingStats stats;
      const std::vector<SE2> poses = smooth_with_odometry(method, odo, config, &stats, stream);
      EXPECT_EQ(stats.poses_downweighted, plain_stats.poses_downweighted) << interval;
      ASSERT_EQ(poses.size(), expected.size());
      for (std::size_t i = 0; i < poses.size(); ++i) {
        ASSERT_EQ(poses[i].vector(), expected[i].vector()) << "interval " << interval << ", pose " << i << ", third " << third;
      }
    }
  }
}

// Where the method's error is white, the third stream finds no slow error worth the name and
// changes little.
TEST(OdometrySmoothing, AThirdStreamLeavesAWhiteMethodError) {
  Rng rng(17);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = jittered(truth, 0.02, 0.015, rng);
  const std::vector<SE2> odometry = odometry_of(truth, 0.02, 0.02, rng);
  const std::vector<SE2> scan = odometry_of(truth, 0.03, 0.03, rng);
  const SmoothedBothWays smoothed = smooth_both_ways(method, odometry, scan);
  EXPECT_LT(smoothed.stats.noise.method_slow.x(), 0.01);
  for (const std::size_t span : {10u, 100u}) {
    EXPECT_LT(relation_error(smoothed.three, truth, span), 1.05 * relation_error(smoothed.two, truth, span)) << span;
  }
}

// A localizer's run: smoothed over the stretches where it was localized, each on its own; where it
// was lost (its pose no measurement) and over a stretch too short to estimate noise from, its
// poses are left exactly as they are.
TEST(OdometrySmoothing, OnlyTheTrustedStretchesAreSmoothed) {
  Rng rng(19);
  const std::vector<SE2> truth = drive();
  std::vector<SE2> method = jittered(truth, 0.02, 0.015, rng);
  const std::vector<SE2> odometry = odometry_of(truth, 0.02, 0.02, rng);
  std::vector<bool> trusted(truth.size(), true);
  for (std::size_t i = 1000; i < 1300; ++i) {  // lost: 3 m off, wandering
    method[i] = SE2(3.0 + rng.gaussian(0, 0.5), rng.gaussian(0, 0.5), rng.gaussian(0, 0.3)) * truth[i];
    trusted[i] = false;
  }
  trusted[2000] = trusted[2020] = false;  // a 19-scan stretch between
  OdometrySmoothingStats stats;
  const std::vector<SE2> smoothed = smooth_trusted_with_odometry(method, odometry, trusted, {}, &stats);
  ASSERT_TRUE(stats.applied);
  EXPECT_EQ(stats.stretches, 3u);  // 0-999, 1300-1999, 2021-: the 19 scans between 2001 and 2020 are too few
  for (std::size_t i = 1000; i < 1300; ++i) EXPECT_EQ(smoothed[i], method[i]) << i;
  for (std::size_t i = 2000; i < 2021; ++i) EXPECT_EQ(smoothed[i], method[i]) << i;
  const auto part = [](const std::vector<SE2>& poses, std::size_t begin, std::size_t end) {
    return std::vector<SE2>(poses.begin() + static_cast<std::ptrdiff_t>(begin), poses.begin() + static_cast<std::ptrdiff_t>(end));
  };
  for (const auto& [begin, end] : {std::pair<std::size_t, std::size_t>{0, 1000}, {1300, 2000}, {2021, truth.size()}}) {
    const double m = relation_error(part(method, begin, end), part(truth, begin, end), 10);
    const double s = relation_error(part(smoothed, begin, end), part(truth, begin, end), 10);
    EXPECT_LT(s, 0.6 * m) << begin << "-" << end << ": method " << m << " smoothed " << s;
  }
  EXPECT_EQ(smooth_trusted_with_odometry(method, odometry, std::vector<bool>(truth.size(), false), {}, &stats), method);
  EXPECT_FALSE(stats.applied);
}

TEST(OdometrySmoothing, LeavesThePosesWhenItCannotOrMayNot) {
  Rng rng(1);
  const std::vector<SE2> truth = drive();
  const std::vector<SE2> method = jittered(truth, 0.02, 0.01, rng);
  OdometrySmoothingStats stats;
  OdometrySmoothingConfig off;
  off.enabled = false;
  EXPECT_EQ(smooth_with_odometry(method, truth, off, &stats), method);
  EXPECT_FALSE(stats.applied);
  EXPECT_EQ(stats.skipped, "disabled");
  const std::vector<SE2> shorter(truth.begin(), truth.end() - 1);
  EXPECT_EQ(smooth_with_odometry(method, shorter, {}, &stats), method);
  EXPECT_FALSE(stats.applied);
  const std::vector<SE2> few(method.begin(), method.begin() + 10);
  EXPECT_EQ(smooth_with_odometry(few, few, {}, &stats), few);
  EXPECT_FALSE(stats.applied);
}

}  // namespace
}  // namespace slam2d
