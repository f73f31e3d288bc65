// SPDX-License-Identifier: BSD-3-Clause
// Scan-to-scan odometry (keyframes as CSM's ROS laser_scan_matcher): its bookkeeping with scripted
// matchers (frames, keyframes, the constant-velocity guess, the gate), and on a simulated run with
// PL-ICP it tracks the truth better than the drifting wheel odometry.

#include "slam2d/registration/scan_odometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <variant>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "slam2d/sim/simulator.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

// A scan of `beams` returns at 3 m (enough points for any matcher call), stamped.
LaserScan flat_scan(double stamp, const SE2& T_robot_sensor = SE2()) {
  LaserScan scan;
  scan.stamp = stamp;
  scan.angle_min = -1.5;
  scan.angle_increment = 0.1;
  scan.range_max = 30.0;
  scan.ranges.assign(31, 3.0);
  scan.T_robot_sensor = T_robot_sensor;
  return scan;
}

MatchResult accepted(const SE2& T) {
  MatchResult result;
  result.T_target_source = T;
  result.converged = true;
  result.inliers = 31;
  result.residual = 0.01;
  return result;
}

TEST(ScanOdometry, MatcherEchoingTheGuessReproducesOdometryWithAMountedSensor) {
  const SE2 T_robot_sensor(0.2, 0.05, 0.1);
  std::vector<SE2> guesses;
  ScanOdometry odometry([&](const PointCloud2&, const PointCloud2&, const SE2& guess) {
    guesses.push_back(guess);
    return accepted(guess);
  });
  const std::vector<SE2> odom = {SE2(5.0, 1.0, 0.3), SE2(5.2, 1.1, 0.35), SE2(5.5, 1.1, 0.5), SE2(5.6, 1.3, 0.9)};
  for (std::size_t k = 0; k < odom.size(); ++k) {
    const SE2 pose = odometry.add(flat_scan(0.1 * static_cast<double>(k), T_robot_sensor), odom[k]);
    EXPECT_TRUE(test::poses_near(pose, odom[k], 1e-12, 1e-12)) << k;  // world = the log's odometry frame
  }
  ASSERT_EQ(guesses.size(), 3u);
  // The guess is the odometry between keyframe and scan, moved into the sensor frames (every
  // step here exceeds the keyframe thresholds, so the keyframe is always the previous scan).
  const SE2 expected = T_robot_sensor.inverse() * odom[1].between(odom[2]) * T_robot_sensor;
  EXPECT_TRUE(test::poses_near(guesses[1], expected, 1e-12, 1e-12));
  EXPECT_EQ(odometry.stats().matches, 3u);
  EXPECT_EQ(odometry.stats().failures, 0u);
  EXPECT_EQ(odometry.stats().keyframes, 4u);
  EXPECT_EQ(odometry.trajectory().size(), 4u);
  EXPECT_DOUBLE_EQ(odometry.trajectory()[3].stamp, 0.3);
}

TEST(ScanOdometry, MatchCorrectsTheOdometryInTheRobotFrame) {
  const SE2 T_robot_sensor(0.3, 0.0, 0.0);
  const SE2 truth_motion(0.2, 0.0, 0.1);  // robot frame
  ScanOdometry odometry([&](const PointCloud2&, const PointCloud2&, const SE2&) {
    return accepted(T_robot_sensor.inverse() * truth_motion * T_robot_sensor);
  });
  odometry.add(flat_scan(0.0, T_robot_sensor), SE2(0.0, 0.0, 0.0));
  const SE2 pose = odometry.add(flat_scan(0.1, T_robot_sensor), SE2(0.25, 0.03, 0.08));  // drifted odometry
  EXPECT_TRUE(test::poses_near(pose, truth_motion, 1e-12, 1e-12)) << pose;
}

TEST(ScanOdometry, ConstantVelocityGuessWithoutOdometry) {
  const SE2 step(0.1, 0.0, 0.05);  // per 0.1 s
  std::vector<SE2> guesses;
  ScanOdometry odometry(
      [&](const PointCloud2&, const PointCloud2&, const SE2& guess) {
        guesses.push_back(guess);
        return accepted(step);
      },
      {.keyframe_distance = 0.0, .keyframe_angle = 0.0});
  for (const double stamp : {0.0, 0.1, 0.3, 2.0}) odometry.add(flat_scan(stamp));
  ASSERT_EQ(guesses.size(), 3u);
  EXPECT_TRUE(test::poses_near(guesses[0], SE2(), 1e-12, 1e-12));  // no velocity yet
  EXPECT_TRUE(test::poses_near(guesses[1], SE2::exp(2.0 * step.log()), 1e-12, 1e-12));  // twice the time step
  EXPECT_TRUE(test::poses_near(guesses[2], SE2(), 1e-12, 1e-12));  // 1.7 s gap: no extrapolation
  EXPECT_TRUE(test::poses_near(odometry.trajectory().back().pose, step * step * step, 1e-12, 1e-12));
  EXPECT_EQ(odometry.stats().keyframes, 4u);  // 0: every scan is a keyframe
}

TEST(ScanOdometry, KeyframeKeptWhileTheRobotBarelyMoves) {
  std::vector<SE2> guesses;
  ScanOdometry odometry([&](const PointCloud2&, const PointCloud2&, const SE2& guess) {
    guesses.push_back(guess);
    return accepted(guess);
  });
  // 3 cm per scan: the keyframe (0.1 m) is renewed at the 4th scan, 9 cm would not do.
  for (int k = 0; k < 6; ++k) odometry.add(flat_scan(0.1 * k), SE2(0.03 * k, 0.0, 0.0));
  ASSERT_EQ(guesses.size(), 5u);
  EXPECT_NEAR(guesses[2].x(), 0.09, 1e-12);  // scan 3 against scan 0
  EXPECT_NEAR(guesses[3].x(), 0.12, 1e-12);  // scan 4 against scan 0, now a new keyframe
  EXPECT_NEAR(guesses[4].x(), 0.03, 1e-12);  // scan 5 against scan 4
  EXPECT_EQ(odometry.stats().keyframes, 2u);
}

TEST(ScanOdometry, GateRejectsImplausibleMatchesAndFallsBackToTheGuess) {
  int call = 0;
  ScanOdometry odometry([&](const PointCloud2&, const PointCloud2&, const SE2& guess) {
    ++call;
    MatchResult result = accepted(guess * SE2(0.01, 0.0, 0.0));
    if (call == 1) result = accepted(guess * SE2(1.0, 0.0, 0.0));  // jumps 1 m from the odometry
    if (call == 2) result.converged = false;
    if (call == 3) result.inliers = 3;
    if (call == 4) result.residual = 0.5;
    if (call == 5) result = accepted(guess * SE2(0.0, 0.0, 0.8));  // turns 0.8 rad more
    return result;
  });
  odometry.add(flat_scan(0.0), SE2());
  for (int k = 1; k <= 6; ++k) {
    const SE2 odom(0.2 * k, 0.0, 0.0);
    const SE2 pose = odometry.add(flat_scan(0.1 * k), odom);
    if (k <= 5) {
      EXPECT_FALSE(odometry.last_accepted()) << k;
      EXPECT_TRUE(test::poses_near(pose, odom, 1e-12, 1e-12)) << k;
    } else {
      EXPECT_TRUE(odometry.last_accepted());
      EXPECT_NEAR(pose.x(), 0.2 * k + 0.01, 1e-12);
    }
  }
  EXPECT_EQ(odometry.stats().failures, 5u);
  EXPECT_EQ(odometry.stats().matches, 6u);
}

TEST(ScanOdometry, ScanWithoutPointsIsNotMatched) {
  ScanOdometry odometry([](const PointCloud2&, const PointCloud2&, const SE2& guess) { return accepted(guess); });
  odometry.add(flat_scan(0.0), SE2());
  LaserScan empty = flat_scan(0.1);
  empty.ranges.assign(31, 30.0);  // all no-return
  const SE2 pose = odometry.add(empty, SE2(0.05, 0.0, 0.0));
  EXPECT_TRUE(test::poses_near(pose, SE2(0.05, 0.0, 0.0), 1e-12, 1e-12));
  EXPECT_EQ(odometry.stats().matches, 0u);
  EXPECT_EQ(odometry.stats().failures, 1u);
}

TEST(ScanOdometry, RemembersWhichScansWereMatchedAndAgainstWhichMount) {
  const SE2 first_mount(0.2, 0.0, 0.1), second_mount(0.1, 0.05, -0.2);
  ScanOdometry odometry([](const PointCloud2&, const PointCloud2&, const SE2& guess) { return accepted(guess); });
  odometry.add(flat_scan(0.0, first_mount), SE2());
  EXPECT_FALSE(odometry.last_matched());  // the first scan has no keyframe to match
  odometry.add(flat_scan(1.0, second_mount), SE2(0.2, 0.0, 0.0));  // 0.2 m/s: trusted, a new keyframe
  EXPECT_TRUE(odometry.last_matched());
  EXPECT_TRUE(test::poses_near(odometry.last_target_T_robot_sensor(), first_mount, 0.0, 0.0));
  LaserScan empty = flat_scan(2.0, first_mount);
  empty.ranges.assign(31, 30.0);  // all no-return
  odometry.add(empty, SE2(0.25, 0.0, 0.0));  // not matched, not far enough for a keyframe
  EXPECT_FALSE(odometry.last_matched());
  odometry.add(flat_scan(3.0, first_mount), SE2(0.4, 0.0, 0.0));
  EXPECT_TRUE(odometry.last_matched());
  EXPECT_TRUE(test::poses_near(odometry.last_target_T_robot_sensor(), second_mount, 0.0, 0.0));  // scan 1, the keyframe
}

// The world position of every point of a target cloud, moved out of the keyframe's sensor frame.
std::vector<Point2> in_world(const PointCloud2& target, const SE2& T_world_sensor) {
  std::vector<Point2> world;
  for (const Point2& p : target.points) world.push_back(T_world_sensor * p);
  return world;
}

TEST(ScanOdometry, TheLocalMapHoldsTheLastKeyframesWhereTheyWereSeen) {
  const SE2 mount(0.2, 0.05, 0.1);
  // Scan k sees a circle of radius 3 + 0.1 k around its sensor: each point names its scan.
  const auto scan = [&](int k) {
    LaserScan s = flat_scan(0.1 * k, mount);
    s.ranges.assign(31, 3.0 + 0.1 * k);
    return s;
  };
  const auto odom = [](int k) { return SE2(0.2 * k, 0.03 * k * k, 0.05 * k); };  // a keyframe every scan
  for (const std::size_t keyframes : {std::size_t{1}, std::size_t{2}, std::size_t{3}}) {
    std::vector<PointCloud2> targets;
    int call = 0;
    ScanOdometry odometry(
        [&](const PointCloud2& target, const PointCloud2&, const SE2& guess) {
          targets.push_back(target);
          MatchResult result = accepted(guess);
          if (++call == 4) result.converged = false;  // scan 4 fails: it starts the local map afresh
          return result;
        },
        {.local_map_keyframes = keyframes});
    for (int k = 0; k <= 5; ++k) odometry.add(scan(k), odom(k));
    ASSERT_EQ(targets.size(), 5u);
    // Scan k (1-based call k) is matched against keyframes k-1, k-2, ... as far as the local map
    // reaches; after the failure of scan 4, scan 5 sees keyframe 4 alone.
    for (int k = 1; k <= 5; ++k) {
      const int newest = k - 1;
      const int reach = k == 5 ? 1 : std::min<int>(static_cast<int>(keyframes), k);
      const PointCloud2& target = targets[static_cast<std::size_t>(k - 1)];
      ASSERT_EQ(target.size(), 31u * static_cast<std::size_t>(reach)) << keyframes << " keyframes, scan " << k;
      const std::vector<Point2> world = in_world(target, odom(newest) * mount);
      for (int m = 0; m < reach; ++m) {
        const SE2 T_world_sensor = odom(newest - m) * mount;  // where scan newest - m was taken
        for (std::size_t j = 0; j < 31; ++j) {
          const Point2& p = world[31 * static_cast<std::size_t>(m) + j];
          // On scan newest - m's circle, around the sensor that saw it.
          EXPECT_NEAR((p - T_world_sensor.translation()).norm(), 3.0 + 0.1 * (newest - m), 1e-9)
              << keyframes << " keyframes, scan " << k << ", keyframe " << newest - m;
        }
      }
    }
  }
}

// (x, y, theta) of A * T * C for a perturbed T, to differentiate numerically.
Eigen::Vector3d between_robots_vector(const SE2& A, const Eigen::Vector3d& t, const SE2& C) {
  const SE2 moved = A * SE2(t.x(), t.y(), t.z()) * C;
  return {moved.x(), moved.y(), moved.theta()};
}

TEST(ScanOdometry, MatchBetweenRobotsPropagatesTheCovarianceThroughTheMounts) {
  const SE2 T_robot_target_sensor(0.3, -0.1, 0.4), T_robot_source_sensor(-0.2, 0.15, -0.3);
  MatchResult match = accepted(SE2(0.5, 0.2, 0.3));
  Eigen::Matrix3d L;
  L << 0.02, 0, 0, 0.005, 0.01, 0, -0.003, 0.002, 0.008;
  match.covariance = L * L.transpose();
  match.weak_direction = Eigen::Vector3d(0.0, 0.0, 1.0);
  const MatchResult moved = match_between_robots(match, T_robot_target_sensor, T_robot_source_sensor);
  EXPECT_TRUE(test::poses_near(moved.T_target_source,
                               T_robot_target_sensor * match.T_target_source * T_robot_source_sensor.inverse(), 1e-12,
                               1e-12));
  // J by central differences.
  const Eigen::Vector3d t(0.5, 0.2, 0.3);
  Eigen::Matrix3d J;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d h = 1e-6 * Eigen::Vector3d::Unit(k);
    J.col(k) = (between_robots_vector(T_robot_target_sensor, t + h, T_robot_source_sensor.inverse()) -
                between_robots_vector(T_robot_target_sensor, t - h, T_robot_source_sensor.inverse())) / 2e-6;
  }
  const Eigen::Matrix3d expected = J * match.covariance * J.transpose();
  EXPECT_LT((moved.covariance - expected).norm(), 1e-9 * expected.norm()) << moved.covariance << "\n" << expected;
  // A rotation about the sensor moves the robot too (the lever arm): the weak direction follows.
  EXPECT_NEAR((moved.weak_direction - (J.col(2) / J.col(2).norm())).norm(), 0.0, 1e-9);
  // Unmounted sensors change nothing; an unknown covariance stays unknown.
  const MatchResult same = match_between_robots(match, SE2(), SE2());
  EXPECT_LT((same.covariance - match.covariance).norm(), 1e-15);
  EXPECT_TRUE(test::poses_near(same.T_target_source, match.T_target_source, 1e-15, 1e-15));
  match.covariance = unknown_covariance();
  EXPECT_EQ(match_between_robots(match, T_robot_target_sensor, T_robot_source_sensor).covariance, unknown_covariance());
}

TEST(ScanOdometry, InvalidSettingsThrow) {
  const Matcher echo = [](const PointCloud2&, const PointCloud2&, const SE2& guess) { return accepted(guess); };
  EXPECT_THROW(ScanOdometry(Matcher{}), Error);
  EXPECT_THROW(ScanOdometry(echo, {.keyframe_distance = -1.0}), Error);
  EXPECT_THROW(ScanOdometry(echo, {.local_map_keyframes = 0}), Error);
  EXPECT_THROW(ScanOdometry(echo, {.min_range = 5.0, .max_range = 5.0}), Error);
  EXPECT_THROW(ScanOdometry(echo, {.max_guess_dt = 0.0}), Error);
  EXPECT_THROW(ScanOdometry(echo, {.min_inlier_fraction = 1.5}), Error);
  EXPECT_THROW(ScanOdometry(echo, {.max_residual = 0.0}), Error);
  EXPECT_THROW(ScanOdometry(echo, {.max_correction_angle = std::nan("")}), Error);
}

// Mean position error (m) of a trajectory against the truth, pose by pose.
double mean_position_error(const std::vector<SE2>& poses, const Trajectory& truth) {
  double sum = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) sum += (poses[k].translation() - truth[k].pose.translation()).norm();
  return sum / static_cast<double>(poses.size());
}

TEST(ScanOdometry, PlIcpOnASimulatedRunTracksTheTruthBetterThanOdometry) {
  SimulationConfig config;
  config.duration = 60.0;
  const SimulatedRun run = simulate(config);
  for (const bool use_odometry : {true, false}) {
    ScanOdometry odometry([](const PointCloud2& target, const PointCloud2& source,
                             const SE2& guess) { return match_pl_icp(target, source, guess); });
    std::vector<SE2> estimate, wheel;
    for (const SensorMessage& message : run.messages) {
      const auto* laser = std::get_if<LaserMessage>(&message);
      if (laser == nullptr) continue;
      estimate.push_back(use_odometry ? odometry.add(laser->scan, laser->odom_pose)
                                      : run.truth[0].pose * odometry.add(laser->scan));
      wheel.push_back(laser->odom_pose);
    }
    ASSERT_EQ(estimate.size(), run.truth.size());
    const double matched = mean_position_error(estimate, run.truth);
    const double raw = mean_position_error(wheel, run.truth);
    // Without odometry the plain stretch of the south corridor (x 6.6 to 8.1 m) leaves the
    // axis to the constant-velocity guess and costs ~0.14 m: better than odometry, not by half.
    EXPECT_LT(matched, (use_odometry ? 0.5 : 1.0) * raw) << (use_odometry ? "with" : "without") << " odometry: " << matched << " m vs "
                                  << raw << " m";
    EXPECT_LE(odometry.stats().failures, odometry.stats().scans / 50);
    EXPECT_GT(odometry.stats().matches, 0u);
  }
}

}  // namespace
}  // namespace slam2d
