// SPDX-License-Identifier: BSD-3-Clause
// The odometry's time offset against the laser (registration/odometry_time_offset.hpp) on
// simulated logs whose odometry was moved in time by a known amount: the offset recovered, a log
// without turns or scans left unjudged, and the compensation (as the log reader applies it) bringing
// the odometry back onto the truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <variant>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/odometry_chain.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/registration/odometry_time_offset.hpp"
#include "slam2d/sim/office_world.hpp"
#include "slam2d/sim/simulator.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

// Two minutes in the office (the first lap and more: every kind of turn), odometry moved by `by` s.
std::vector<SensorMessage> office_log(double by, double duration = 120.0) {
  SimulationConfig config;
  config.duration = duration;
  config.seed = 3;
  std::vector<SensorMessage> messages = simulate(config).messages;
  shift_scan_odometry(messages, by);
  return messages;
}

// rad: the mean disagreement of the heading change over 0.5 s (5 scans) between each scan's
// odometry and the truth.
double heading_change_error(const std::vector<SensorMessage>& messages, const Trajectory& truth) {
  std::vector<double> odometry;
  for (const SensorMessage& message : messages) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) odometry.push_back(laser->odom_pose.theta());
  }
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 5; i < odometry.size() && i < truth.size(); ++i) {
    const double measured = angle_difference(odometry[i], odometry[i - 5]);
    const double actual = angle_difference(truth[i].pose.theta(), truth[i - 5].pose.theta());
    sum += std::abs(angle_difference(measured, actual));
    ++count;
  }
  return sum / static_cast<double>(count);
}

class ShiftedOdometry : public ::testing::TestWithParam<double> {};

TEST_P(ShiftedOdometry, TheOffsetIsRecoveredWithinFiftyMilliseconds) {
  const double shift = GetParam();
  const OdometryTimeOffset estimate = estimate_odometry_time_offset(office_log(shift));
  ASSERT_TRUE(estimate.estimated) << estimate.reason;
  EXPECT_NEAR(estimate.offset, shift, 0.05);
  EXPECT_LT(estimate.uncertainty, 0.03);
  EXPECT_EQ(estimate.significant, shift != 0.0);
  EXPECT_LE(estimate.pairs, OdometryTimeOffsetConfig{}.max_pairs);
  EXPECT_GT(estimate.turning_pairs, 30u);
  if (shift != 0.0) {
    EXPECT_LT(estimate.cost_at_best, 0.5 * estimate.cost_at_zero);  // the minimum is real
  }
}

INSTANTIATE_TEST_SUITE_P(Office, ShiftedOdometry, ::testing::Values(0.6, -0.4, 0.0, 1.0));

// odometry_time_offset_scans names every scan the estimate matches and no more than its windows
// hold: with the others' ranges dropped (what slam2d map reads of a long log) the estimate is the
// same to the bit; with one of the named scans dropped too, it is not.
TEST(OdometryTimeOffset, TheScansItNamesAreAllItReads) {
  const OdometryTimeOffsetConfig config{.max_pairs = 200};  // windows spread over the log
  const std::vector<SensorMessage> messages = office_log(0.6);
  const std::vector<std::size_t> used = odometry_time_offset_scans(messages, config);
  std::size_t lasers = 0;
  for (const SensorMessage& message : messages) lasers += std::holds_alternative<LaserMessage>(message) ? 1 : 0;
  ASSERT_FALSE(used.empty());
  EXPECT_LE(used.size(), 2 * config.max_pairs);
  EXPECT_LT(used.size(), lasers / 2);
  EXPECT_TRUE(std::is_sorted(used.begin(), used.end()));
  EXPECT_EQ(std::adjacent_find(used.begin(), used.end()), used.end());
  std::vector<SensorMessage> stripped = messages;
  std::size_t next = 0;
  for (std::size_t i = 0; i < stripped.size(); ++i) {
    auto* laser = std::get_if<LaserMessage>(&stripped[i]);
    if (next < used.size() && used[next] == i) {
      ASSERT_NE(laser, nullptr);
      ++next;
    } else if (laser != nullptr) {
      laser->scan.ranges.clear();
    }
  }
  const OdometryTimeOffset full = estimate_odometry_time_offset(messages, config);
  const OdometryTimeOffset light = estimate_odometry_time_offset(stripped, config);
  ASSERT_TRUE(full.estimated) << full.reason;
  EXPECT_EQ(light.offset, full.offset);
  EXPECT_EQ(light.uncertainty, full.uncertainty);
  EXPECT_EQ(light.pairs, full.pairs);
  std::get<LaserMessage>(stripped[used[used.size() / 2]]).scan.ranges.clear();
  EXPECT_LT(estimate_odometry_time_offset(stripped, config).pairs, full.pairs);
  // Read as slam2d map reads a long log: every message's stamp and pose, then the named scans.
  TimeOffsetInput streamed;
  for (const SensorMessage& message : messages) streamed.add(message, /*with_scan=*/false);
  EXPECT_EQ(odometry_time_offset_scans(streamed, config), used);
  for (const std::size_t index : used) ASSERT_TRUE(streamed.set_scan(index, std::get<LaserMessage>(messages[index]).scan));
  const OdometryTimeOffset read_twice = estimate_odometry_time_offset(streamed, config);
  EXPECT_EQ(read_twice.offset, full.offset);
  EXPECT_EQ(read_twice.uncertainty, full.uncertainty);
  EXPECT_EQ(read_twice.pairs, full.pairs);
  const auto not_a_scan = std::find_if(messages.begin(), messages.end(), [](const SensorMessage& message) {
    return !std::holds_alternative<LaserMessage>(message);
  });
  ASSERT_NE(not_a_scan, messages.end());
  EXPECT_FALSE(streamed.set_scan(static_cast<std::size_t>(not_a_scan - messages.begin()), LaserScan{}));
  EXPECT_FALSE(streamed.set_scan(messages.size(), LaserScan{}));
  LaserScan another = std::get<LaserMessage>(messages[used.front()]).scan;
  another.stamp += 1.0;  // the log changed between the two readings
  EXPECT_FALSE(streamed.set_scan(used.front(), another));
}

TEST(OdometryTimeOffset, AStraightDriveWithoutTurnsIsNotEstimated) {
  World world = make_office_world();
  world.route = {{4.0, 6.0}, {20.0, 6.0}};  // straight east along the corridor; 20 s end before the turn
  SimulationConfig config;
  config.duration = 20.0;
  std::vector<SensorMessage> messages = simulate(config, world).messages;
  shift_scan_odometry(messages, 0.6);
  const OdometryTimeOffset estimate = estimate_odometry_time_offset(messages);
  EXPECT_FALSE(estimate.estimated);
  EXPECT_FALSE(estimate.significant);
  EXPECT_EQ(estimate.offset, 0.0);
  EXPECT_NE(estimate.reason.find("too few turns"), std::string::npos) << estimate.reason;
  EXPECT_GT(estimate.pairs, 50u);  // the scans were matched: it is the turns that are missing
}

TEST(OdometryTimeOffset, LogsItCannotJudgeAreNotEstimatedAndNothingThrows) {
  EXPECT_FALSE(estimate_odometry_time_offset(std::vector<SensorMessage>{}).estimated);
  EXPECT_FALSE(estimate_odometry_time_offset(TimeOffsetInput{}).estimated);
  std::vector<SensorMessage> messages = office_log(0.0, 3.0);  // 30 scans: too few windows
  EXPECT_FALSE(estimate_odometry_time_offset(messages).estimated);
  messages = office_log(0.0, 60.0);
  for (SensorMessage& message : messages) {  // every stamp 0, as in the Örebro corrected log
    if (auto* laser = std::get_if<LaserMessage>(&message)) laser->scan.stamp = 0.0;
  }
  const OdometryTimeOffset zero_stamps = estimate_odometry_time_offset(messages);
  EXPECT_FALSE(zero_stamps.estimated);
  EXPECT_EQ(zero_stamps.offset, 0.0);
  EXPECT_FALSE(zero_stamps.reason.empty());
  EXPECT_THROW(estimate_odometry_time_offset(messages, {.grid_step = 0.0}), Error);
}

TEST(OdometryTimeOffset, CompensationPutsTheOdometryBackOntoTheTruth) {
  SimulationConfig config;
  config.duration = 120.0;
  config.seed = 3;
  const SimulatedRun run = simulate(config);
  std::vector<SensorMessage> shifted = run.messages;
  shift_scan_odometry(shifted, 0.6);
  const OdometryTimeOffset estimate = estimate_odometry_time_offset(shifted);
  ASSERT_TRUE(estimate.significant) << estimate.reason;
  std::vector<SensorMessage> compensated = shifted;
  shift_scan_odometry(compensated, -estimate.offset);
  const double clean = heading_change_error(run.messages, run.truth);
  const double off = heading_change_error(shifted, run.truth);
  const double back = heading_change_error(compensated, run.truth);
  EXPECT_GT(off, 4.0 * clean);
  EXPECT_LT(back, 1.5 * clean + 0.002);
}

TEST(OdometryTimeOffset, TheLogReaderCompensatesAsItReads) {
  const test::TempDir dir;
  const std::string path = dir.file("shifted.clf");
  const std::vector<SensorMessage> shifted = office_log(0.6, 30.0);
  write_carmen_log(path, {}, shifted);
  LogReader as_logged(path);
  std::vector<SensorMessage> expected = read_all(as_logged);
  shift_scan_odometry(expected, -0.6);
  LogReaderOptions options;
  options.odometry_time_offset = 0.6;
  LogReader reader(path, options);
  const std::vector<SensorMessage> read = read_all(reader);
  EXPECT_DOUBLE_EQ(reader.progress(), 1.0);
  ASSERT_EQ(read.size(), expected.size());
  std::size_t scans = 0;
  for (std::size_t i = 0; i < read.size(); ++i) {
    if (const auto* laser = std::get_if<LaserMessage>(&read[i])) {
      EXPECT_TRUE(laser->odom_pose == std::get<LaserMessage>(expected[i]).odom_pose) << i;
      ++scans;
    }
  }
  EXPECT_EQ(scans, 301u);
  options.odometry_time_offset = std::nan("");
  EXPECT_THROW(LogReader(path, options), Error);
}

}  // namespace
}  // namespace slam2d
