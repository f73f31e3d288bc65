// SPDX-License-Identifier: BSD-3-Clause
// `slam2d map`'s odometry sources, the time-based scan subset and the 2015 chain (hector+graph,
// hector+rbpf) on a simulated log with its truth: each output is what it says it is, the chain's
// fused trajectory is dense and near the truth, and what cannot be done is refused.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "slam2d/eval/ate.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/log_writer.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::json_number;
using test::run_command;

using test::slam2d;

class PipelineCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { sim_ = new test::SimulatedLog(60, 3); }
  static void TearDownTestSuite() { delete sim_; }
  static std::string log() { return sim_->log(); }
  static std::string truth() { return sim_->truth(); }
  static test::SimulatedLog* sim_;

  static CommandResult map(const TempDir& out, const std::string& arguments) {
    return run_command(slam2d("map --quiet --json " + log() + " --out " + out.path().string() + " " + arguments));
  }
  static double ate_rmse(const std::string& trajectory) {
    return absolute_trajectory_error(read_trajectory(trajectory), read_trajectory(truth())).rmse;
  }
};
test::SimulatedLog* PipelineCli::sim_ = nullptr;

TEST_F(PipelineCli, ATrajectoryAsOdometryIsWhatTheScansCarry) {
  // Mapping by "odometry" from the truth gives back the truth; from the log, the log's drift.
  TempDir from_truth;
  const CommandResult result = map(from_truth, "--method odometry --odometry-source " + truth());
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  EXPECT_LT(ate_rmse(from_truth.file("trajectory.txt")), 1e-6);
  EXPECT_EQ(json_number(result.output, "scans_outside_odometry"), 0.0);
  TempDir from_log;
  ASSERT_EQ(map(from_log, "--method odometry").exit_code, 0);
  EXPECT_GT(ate_rmse(from_log.file("trajectory.txt")), 0.05);
}

TEST_F(PipelineCli, ScansOutsideTheTrajectorysSpanAreLeftOutAndCounted) {
  const Trajectory truth_poses = read_trajectory(truth());
  Trajectory first_half;
  for (std::size_t i = 0; i < truth_poses.size() / 2; ++i) first_half.push_back(truth_poses[i].stamp, truth_poses[i].pose);
  TempDir out;
  write_trajectory(out.file("half.txt"), first_half, TrajectoryFormat::kText);
  const CommandResult result = map(out, "--method odometry --odometry-source " + out.file("half.txt"));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const double scans = *json_number(result.output, "scans");
  const double outside = *json_number(result.output, "scans_outside_odometry");
  EXPECT_NEAR(scans, static_cast<double>(first_half.size()), 1.0);
  EXPECT_NEAR(scans + outside, static_cast<double>(truth_poses.size()), 1.0);
  EXPECT_NE(result.output.find("outside the time span"), std::string::npos) << "a warning in the summary";
}

TEST_F(PipelineCli, TheScanRateKeepsOneScanPerSlot) {
  TempDir out;
  const CommandResult result = map(out, "--method graph --scan-rate 2");
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const Trajectory trajectory = read_trajectory(out.file("trajectory.txt"));
  const Trajectory truth_poses = read_trajectory(truth());
  const double duration = truth_poses.back().stamp - truth_poses.front().stamp;
  EXPECT_NEAR(static_cast<double>(trajectory.size()), 2.0 * duration, 2.0);
  for (std::size_t i = 1; i < trajectory.size(); ++i) {  // one scan per half-second slot from the first
    const double slot = std::floor(2.0 * (trajectory[i].stamp - trajectory[0].stamp));
    const double previous = std::floor(2.0 * (trajectory[i - 1].stamp - trajectory[0].stamp));
    EXPECT_EQ(slot, previous + 1.0) << i;
  }
  EXPECT_LT(ate_rmse(out.file("trajectory.txt")), 0.1);
}

TEST_F(PipelineCli, HectorPlusGraphIsDenseAndNearTheTruthWithoutWheelOdometry) {
  TempDir out;
  const CommandResult result = map(out, "--method hector+graph");
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const Trajectory truth_poses = read_trajectory(truth());
  const Trajectory fused = read_trajectory(out.file("trajectory.txt"));
  const Trajectory sparse = read_trajectory(out.file("sparse_trajectory.txt"));
  const Trajectory dense = read_trajectory(out.file("hector_trajectory.txt"));
  EXPECT_EQ(fused.size(), truth_poses.size()) << "one pose per scan";
  EXPECT_EQ(dense.size(), truth_poses.size());
  const double duration = truth_poses.back().stamp - truth_poses.front().stamp;
  EXPECT_NEAR(static_cast<double>(sparse.size()), 3.0 * duration, 3.0) << "the sparse method sees 3 scans a second";
  EXPECT_LT(ate_rmse(out.file("trajectory.txt")), 0.1);
  EXPECT_LT(ate_rmse(out.file("sparse_trajectory.txt")), 0.1);
  EXPECT_EQ(json_number(result.output, "sparse_scans"), static_cast<double>(sparse.size()));
  EXPECT_NE(result.output.find("\"odometry_source\": \"hector\""), std::string::npos) << result.output;
}

TEST_F(PipelineCli, TheChainIsImmuneToWheelOdometryFaults) {
  // Stalls and resets of the odometry (docs/faults.md) change graph SLAM's run, not the chain's.
  TempDir out;
  const std::string faulty = out.file("faulty.clf");
  const CommandResult perturbed = run_command(slam2d("perturb --quiet " + log() + " --out " + faulty +
                                                     " --fault stall:every=10,duration=2 --fault odom-reset:every=20"));
  ASSERT_EQ(perturbed.exit_code, 0) << perturbed.errors;
  const auto run = [&](const std::string& input, const std::string& method, const std::string& name) {
    const CommandResult result =
        run_command(slam2d("map --quiet " + input + " --method " + method + " --out " + out.file(name)));
    EXPECT_EQ(result.exit_code, 0) << result.errors;
    std::ifstream in(out.file(name) + "/trajectory.txt");
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  EXPECT_EQ(run(log(), "hector+graph", "clean"), run(faulty, "hector+graph", "faulty"));
  EXPECT_NE(run(log(), "graph", "graph_clean"), run(faulty, "graph", "graph_faulty"));
}

TEST_F(PipelineCli, TheParticleFilterRunsWithoutWheelOdometry) {
  TempDir chain;
  const CommandResult fused = map(chain, "--method hector+rbpf --particles 10 --seed 2");
  ASSERT_EQ(fused.exit_code, 0) << fused.errors;
  EXPECT_LT(ate_rmse(chain.file("trajectory.txt")), 0.15);
  TempDir none;
  const CommandResult alone = map(none, "--method rbpf --odometry-source none --particles 10 --seed 2");
  ASSERT_EQ(alone.exit_code, 0) << alone.errors;
  EXPECT_NE(alone.output.find("\"odometry_source\": \"hector\""), std::string::npos) << alone.output;
  EXPECT_LT(ate_rmse(none.file("trajectory.txt")), 0.15);
}

// The RBPF's learnt odometry prior weighs the odometry as a sensor of its own: on the log's wheel
// odometry it learns (and reports) its scales; on Hector's poses, from the same scans, it is not
// used, whatever the preset says.
TEST_F(PipelineCli, TheLearntOdometryPriorIsForAnOdometryOfItsOwn) {
  TempDir config;
  {
    std::ofstream out(config.file("rbpf.yaml"));
    out << "method: rbpf\nscan_odometry_prior_from_motion_noise: true\nscan_odometry_calibration:\n  window: 100\n";
  }
  const std::string arguments = " --particles 5 --seed 2 --config " + config.file("rbpf.yaml");
  TempDir wheel;
  const CommandResult learnt = map(wheel, "--method rbpf" + arguments);
  ASSERT_EQ(learnt.exit_code, 0) << learnt.errors;
  EXPECT_NE(learnt.output.find("\"odometry_noise_scale_translation\""), std::string::npos) << learnt.output;
  EXPECT_GT(json_number(learnt.output, "odometry_calibration_stretches").value_or(0.0), 10.0);
  TempDir chain;
  const CommandResult fixed = map(chain, "--method hector+rbpf" + arguments);
  ASSERT_EQ(fixed.exit_code, 0) << fixed.errors;
  EXPECT_EQ(fixed.output.find("odometry_noise_scale"), std::string::npos) << fixed.output;
  EXPECT_EQ(fixed.output.find("odometry_calibration"), std::string::npos) << fixed.output;
}

// The same for graph SLAM's tracker, whose calibration is on by default: it learns the wheel
// odometry's systematic error, and Hector's poses, which have none of their own, teach it nothing.
TEST_F(PipelineCli, TheTrackersCalibrationIsForAnOdometryOfItsOwn) {
  TempDir wheel;
  const CommandResult learnt = map(wheel, "--method graph");
  ASSERT_EQ(learnt.exit_code, 0) << learnt.errors;
  EXPECT_GT(json_number(learnt.output, "odometry_calibration_stretches").value_or(0.0), 10.0) << learnt.output;
  TempDir chain;
  const CommandResult fixed = map(chain, "--method hector+graph");
  ASSERT_EQ(fixed.exit_code, 0) << fixed.errors;
  EXPECT_EQ(fixed.output.find("odometry_calibration"), std::string::npos) << fixed.output;
}

TEST_F(PipelineCli, WhatCannotBeDoneIsRefusedWithoutOutput) {
  for (const std::string& arguments :
       {std::string("--method graph --odometry-source /nonexistent/odometry.txt"), std::string("--method graph --scan-rate 0"),
        std::string("--method hector+graph --no-odometry"), std::string("--method hector+rbpf --odometry-source none"),
        std::string("--method odometry --odometry-source none")}) {
    TempDir out;
    const CommandResult result = map(out, arguments);
    EXPECT_NE(result.exit_code, 0) << arguments;
    EXPECT_FALSE(result.errors.empty()) << arguments;
    EXPECT_FALSE(std::filesystem::exists(out.file("trajectory.txt"))) << arguments;
  }
}

TEST_F(PipelineCli, TheLogsImuReachesHector) {
  // The simulated log as an MCAP bag with an IMU reading before every scan.
  LogReader reader(log());
  std::vector<SensorMessage> messages;
  std::size_t scans = 0;
  while (auto message = reader.next()) {
    if (const auto* laser = std::get_if<LaserMessage>(&*message)) {
      messages.push_back(ImuMessage{.reading = {.stamp = laser->scan.stamp, .roll = 0.01, .pitch = -0.02, .yaw_rate = 0.0}});
      ++scans;
    }
    messages.push_back(*message);
  }
  TempDir out;
  const std::string bag = out.file("with_imu.mcap");
  ASSERT_EQ(write_log(bag, LogFormat::kMcap, messages).imu, scans);
  const CommandResult result =
      run_command(slam2d("map --quiet --json " + bag + " --method hector --odometry-source none --out " + out.file("run")));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  EXPECT_EQ(json_number(result.output, "imu_scans"), static_cast<double>(scans));
  TempDir plain;
  const CommandResult without = map(plain, "--method hector --odometry-source none");
  EXPECT_EQ(json_number(without.output, "imu_scans"), 0.0);
}

TEST_F(PipelineCli, EvalMeasuresTheRpeWindowInTime) {
  TempDir out;
  ASSERT_EQ(map(out, "--method odometry").exit_code, 0);
  const CommandResult self = run_command(slam2d("eval --json " + truth() + " --reference " + truth() +
                                                " --rpe-window time --rpe-delta 0.2"));
  ASSERT_EQ(self.exit_code, 0) << self.errors;
  EXPECT_EQ(json_number(self.output, "rpe_delta_s"), 0.2);
  EXPECT_NEAR(*json_number(self.output, "rpe_trans_mean"), 0.0, 1e-9);
  const CommandResult short_window = run_command(slam2d("eval --json " + out.file("trajectory.txt") + " --reference " +
                                                        truth() + " --rpe-window time --rpe-delta 0.2"));
  const CommandResult long_window = run_command(slam2d("eval --json " + out.file("trajectory.txt") + " --reference " +
                                                       truth() + " --rpe-window time --rpe-delta 10"));
  ASSERT_EQ(short_window.exit_code, 0) << short_window.errors;
  EXPECT_GT(*json_number(short_window.output, "rpe_pairs"), *json_number(long_window.output, "rpe_pairs"));
  EXPECT_LT(*json_number(short_window.output, "rpe_trans_mean"), *json_number(long_window.output, "rpe_trans_mean"))
      << "odometry drifts: the error grows with the window";
}

}  // namespace
}  // namespace slam2d
