// SPDX-License-Identifier: BSD-3-Clause
// What the commands say about a match's certainty: odometry --covariance-csv and slam2d match on
// simulated logs. A long featureless corridor must come out degenerate along its axis with the
// larger variance along it; a room with corners must not; slam2d match must recover the true
// relative pose of two scans; the JSON must parse; bad indices and logs must fail clearly.

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/sim/simulator.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::json_number;
using test::run_command;

using test::slam2d;

World box_world(const std::string& name, const std::vector<WallSegment>& walls, std::vector<Eigen::Vector2d> route) {
  World world;
  world.name = name;
  world.walls = walls;
  for (const WallSegment& wall : walls) {
    world.bounds.extend(wall.a);
    world.bounds.extend(wall.b);
  }
  world.route = std::move(route);
  return world;
}

// A 100 m x 2 m corridor driven between x = 35 and 65: the end walls stay beyond the laser's 30 m.
World corridor_world() {
  return box_world("corridor",
                   {{{0, -1}, {100, -1}}, {{0, 1}, {100, 1}}, {{0, -1}, {0, 1}}, {{100, -1}, {100, 1}}},
                   {{35, 0}, {65, 0}});
}

// A 10 m x 8 m room with a 1 m pillar: corners everywhere.
World room_world() {
  return box_world("room",
                   {{{0, 0}, {10, 0}}, {{10, 0}, {10, 8}}, {{10, 8}, {0, 8}}, {{0, 8}, {0, 0}},
                    {{4.5, 3.5}, {5.5, 3.5}}, {{5.5, 3.5}, {5.5, 4.5}}, {{5.5, 4.5}, {4.5, 4.5}}, {{4.5, 4.5}, {4.5, 3.5}}},
                   {{2, 2}, {8, 2}, {8, 6}, {2, 6}});
}

void write_run(const World& world, double duration, const std::string& log, const std::string& truth) {
  SimulationConfig config;
  config.duration = duration;
  config.seed = 3;
  const SimulatedRun run = simulate(config, world);
  write_carmen_log(log, run_comments(run.config), run.messages);
  write_trajectory(truth, run.truth);
}

// The CSV as rows of cells, the header first.
std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream stream(line);
    std::string cell;
    while (std::getline(stream, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

// A strict JSON syntax check (objects, arrays, strings, numbers, true/false/null).
class JsonChecker {
 public:
  explicit JsonChecker(const std::string& text) : s_(text) {}
  bool valid() {
    if (!value()) return false;
    space();
    return i_ == s_.size();
  }

 private:
  void space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool literal(const std::string& word) {
    if (s_.compare(i_, word.size(), word) != 0) return false;
    i_ += word.size();
    return true;
  }
  bool string() {
    if (s_[i_] != '"') return false;
    for (++i_; i_ < s_.size(); ++i_) {
      if (s_[i_] == '\\') ++i_;
      else if (s_[i_] == '"') return ++i_, true;
    }
    return false;
  }
  bool number() {
    const char* begin = s_.c_str() + i_;
    char* end = nullptr;
    std::strtod(begin, &end);
    if (end == begin || !(std::isdigit(static_cast<unsigned char>(*begin)) || *begin == '-')) return false;
    i_ += static_cast<std::size_t>(end - begin);
    return true;
  }
  bool sequence(char close, bool keyed) {
    ++i_;
    space();
    if (i_ < s_.size() && s_[i_] == close) return ++i_, true;
    while (true) {
      space();
      if (keyed) {
        if (i_ >= s_.size() || !string()) return false;
        space();
        if (i_ >= s_.size() || s_[i_++] != ':') return false;
      }
      if (!value()) return false;
      space();
      if (i_ >= s_.size()) return false;
      if (s_[i_] == close) return ++i_, true;
      if (s_[i_++] != ',') return false;
    }
  }
  bool value() {
    space();
    if (i_ >= s_.size()) return false;
    switch (s_[i_]) {
      case '{': return sequence('}', true);
      case '[': return sequence(']', false);
      case '"': return string();
      case 't': return literal("true");
      case 'f': return literal("false");
      case 'n': return literal("null");
      default: return number();
    }
  }
  const std::string& s_;
  std::size_t i_ = 0;
};

bool json_true(const std::string& json, const std::string& key) {
  return json.find("\"" + key + "\": true") != std::string::npos;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values.empty() ? std::nan("") : values[values.size() / 2];
}

class CovarianceCliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    write_run(corridor_world(), 40.0, corridor_log(), dir_->file("corridor_truth.txt"));
    write_run(room_world(), 40.0, room_log(), room_truth());
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string corridor_log() { return dir_->file("corridor.clf"); }
  static std::string room_log() { return dir_->file("room.clf"); }
  static std::string room_truth() { return dir_->file("room_truth.txt"); }
  static TempDir* dir_;

  struct Run {
    CommandResult result;
    std::vector<std::vector<std::string>> csv;
  };
  static Run odometry(const std::string& log, const std::string& name) {
    const std::string csv = dir_->file(name + "_cov.csv");
    Run run;
    run.result = run_command(slam2d("odometry --quiet --json " + log + " --out " + dir_->file(name + ".txt") +
                                    " --covariance-csv " + csv));
    run.csv = read_csv(csv);
    return run;
  }
};
TempDir* CovarianceCliTest::dir_ = nullptr;

// Column indices of the CSV (covariance_csv_header).
enum Column { kIndex, kStamp, kStatus, kX, kY, kTheta, kConverged, kIterations, kInliers, kResidual, kXX, kXY, kXT, kYY,
              kYT, kTT, kSigmaTrans, kSigmaTheta, kDegenerate, kRatio, kMinEigenvalue, kWeakX, kWeakY, kWeakTheta, kTarget,
              kColumns };

TEST_F(CovarianceCliTest, CorridorIsDegenerateAlongItsAxisWithTheLargerVarianceThere) {
  const Run run = odometry(corridor_log(), "corridor");
  ASSERT_EQ(run.result.exit_code, 0) << run.result.errors;
  ASSERT_TRUE(JsonChecker(run.result.output).valid()) << run.result.output;
  const auto scans = json_number(run.result.output, "scans");
  ASSERT_TRUE(scans);
  ASSERT_EQ(run.csv.size(), static_cast<std::size_t>(*scans) + 1);  // the header and one row per scan
  EXPECT_EQ(run.csv[0].size(), static_cast<std::size_t>(kColumns));
  std::size_t matched = 0, degenerate = 0;
  std::vector<double> along_over_across, weak_along;
  for (std::size_t k = 1; k < run.csv.size(); ++k) {
    const std::vector<std::string>& row = run.csv[k];
    ASSERT_EQ(row.size(), static_cast<std::size_t>(kColumns)) << k;
    EXPECT_EQ(std::stoul(row[kIndex]), k - 1);
    if (row[kStatus] != "matched" && row[kStatus] != "failed") continue;
    ++matched;
    if (row[kDegenerate] == "1") ++degenerate;
    EXPECT_LT(std::stod(row[kRatio]), 0.01) << k;
    along_over_across.push_back(std::stod(row[kXX]) / std::stod(row[kYY]));
    weak_along.push_back(std::abs(std::stod(row[kWeakX])));
  }
  EXPECT_EQ(run.csv[1][kStatus], "first");
  ASSERT_GT(matched, 300u);
  EXPECT_EQ(degenerate, matched);
  EXPECT_EQ(json_number(run.result.output, "degenerate_scans"), static_cast<double>(degenerate));
  // In the keyframe's robot frame, which drives along the corridor, its axis is x.
  EXPECT_GT(median(along_over_across), 100.0);
  EXPECT_GT(median(weak_along), 0.9);
}

TEST_F(CovarianceCliTest, RoomWithCornersIsNotDegenerate) {
  const Run run = odometry(room_log(), "room");
  ASSERT_EQ(run.result.exit_code, 0) << run.result.errors;
  ASSERT_TRUE(JsonChecker(run.result.output).valid()) << run.result.output;
  const auto scans = json_number(run.result.output, "scans");
  ASSERT_TRUE(scans);
  ASSERT_EQ(run.csv.size(), static_cast<std::size_t>(*scans) + 1);
  std::size_t matched = 0, degenerate = 0;
  for (std::size_t k = 1; k < run.csv.size(); ++k) {
    const std::vector<std::string>& row = run.csv[k];
    ASSERT_EQ(row.size(), static_cast<std::size_t>(kColumns)) << k;
    if (row[kStatus] != "matched") continue;
    ++matched;
    if (row[kDegenerate] == "1") ++degenerate;
    EXPECT_GT(std::stod(row[kRatio]), 0.01) << k;
    // A well constrained match: millimetres and hundredths of a degree, symmetric, positive.
    const double xx = std::stod(row[kXX]), yy = std::stod(row[kYY]), tt = std::stod(row[kTT]), xy = std::stod(row[kXY]);
    EXPECT_GT(xx, 0.0);
    EXPECT_GT(yy, 0.0);
    EXPECT_GT(tt, 0.0);
    EXPECT_LT(xy * xy, xx * yy);
    EXPECT_LT(std::stod(row[kSigmaTrans]), 0.02) << k;
  }
  ASSERT_GT(matched, 300u);
  EXPECT_EQ(degenerate, 0u);
  EXPECT_EQ(json_number(run.result.output, "degenerate_scans"), 0.0);
  const auto sigma = json_number(run.result.output, "sigma_trans_median_m");
  ASSERT_TRUE(sigma);
  EXPECT_GT(*sigma, 0.0);
  EXPECT_LT(*sigma, 0.02);
  const auto sigma_p95 = json_number(run.result.output, "sigma_trans_p95_m");
  ASSERT_TRUE(sigma_p95);
  EXPECT_GE(*sigma_p95, *sigma);
  EXPECT_TRUE(json_number(run.result.output, "sigma_theta_median_deg"));
}

// The target column names the keyframe each scan was matched against: an accepted match (the
// default runs without fusion) places its scan at the target's pose composed with the match, so
// the column and the match's pose rebuild the written trajectory; keyframes only move forward.
TEST_F(CovarianceCliTest, TargetColumnAndMatchRebuildTheTrajectory) {
  const Run run = odometry(room_log(), "room_chain");
  ASSERT_EQ(run.result.exit_code, 0) << run.result.errors;
  const Trajectory trajectory = read_trajectory(dir_->file("room_chain.txt"));
  ASSERT_EQ(run.csv.size(), trajectory.size() + 1);
  EXPECT_EQ(run.csv[0].back(), "target");
  EXPECT_EQ(run.csv[1][kTarget], "");  // the first scan is matched against nothing
  std::size_t checked = 0, previous_target = 0;
  std::vector<std::size_t> targets;
  for (std::size_t k = 2; k < run.csv.size(); ++k) {
    const std::vector<std::string>& row = run.csv[k];
    ASSERT_EQ(row.size(), static_cast<std::size_t>(kColumns)) << k;
    if (row[kStatus] != "matched") continue;
    const std::size_t index = std::stoul(row[kIndex]), target = std::stoul(row[kTarget]);
    ASSERT_LT(target, index);
    EXPECT_GE(target, previous_target) << k;
    previous_target = target;
    targets.push_back(target);
    const SE2 match(std::stod(row[kX]), std::stod(row[kY]), std::stod(row[kTheta]));
    const SE2 rebuilt = trajectory[target].pose * match;
    EXPECT_NEAR(rebuilt.x(), trajectory[index].pose.x(), 1e-9) << k;
    EXPECT_NEAR(rebuilt.y(), trajectory[index].pose.y(), 1e-9) << k;
    EXPECT_NEAR(angle_difference(rebuilt.theta(), trajectory[index].pose.theta()), 0.0, 1e-9) << k;
    ++checked;
  }
  ASSERT_GT(checked, 300u);
  // Keyframes (0.1 m / 10 deg apart by default) are fewer than the scans, more than one.
  std::sort(targets.begin(), targets.end());
  const auto keyframes = static_cast<std::size_t>(std::unique(targets.begin(), targets.end()) - targets.begin());
  EXPECT_GT(keyframes, 10u);
  EXPECT_LT(keyframes, checked);
  // Every scan a keyframe: each is matched against the one before.
  const std::string csv = dir_->file("room_every_cov.csv");
  const CommandResult every = run_command(slam2d("odometry --quiet " + room_log() + " --keyframe 0 --out " +
                                                 dir_->file("room_every.txt") + " --covariance-csv " + csv));
  ASSERT_EQ(every.exit_code, 0) << every.errors;
  const auto rows = read_csv(csv);
  ASSERT_GT(rows.size(), 300u);
  for (std::size_t k = 2; k < rows.size(); ++k) {
    if (rows[k][kStatus] != "matched" && rows[k][kStatus] != "failed") continue;
    EXPECT_EQ(std::stoul(rows[k][kTarget]), std::stoul(rows[k][kIndex]) - 1) << k;
  }
}

TEST_F(CovarianceCliTest, MatchRecoversTheTrueRelativePose) {
  const Trajectory truth = read_trajectory(room_truth());
  ASSERT_GT(truth.size(), 60u);
  const std::size_t target = 40, source = 52;
  const SE2 expected = truth[target].pose.between(truth[source].pose);
  ASSERT_GT(expected.translation().norm(), 0.3);  // a real motion, not the identity
  // From the odometry guess (the default) and from a guess 0.3 m and 0.1 rad off.
  const SE2 off = expected * SE2(0.3, -0.2, 0.1);
  std::ostringstream off_guess;
  off_guess.precision(17);
  off_guess << " --guess " << off.x() << "," << off.y() << "," << off.theta();
  for (const std::string& guess : {std::string(), off_guess.str()}) {
    const CommandResult result = run_command(slam2d("match --json " + room_log() + " --target " + std::to_string(target) +
                                                    " --source " + std::to_string(source) + guess));
    ASSERT_EQ(result.exit_code, 0) << result.errors;
    ASSERT_TRUE(JsonChecker(result.output).valid()) << result.output;
    const std::size_t pose = result.output.find("\"pose\"");
    ASSERT_NE(pose, std::string::npos);
    const std::string after = result.output.substr(pose);
    const auto x = json_number(after, "x"), y = json_number(after, "y"), theta = json_number(after, "theta");
    ASSERT_TRUE(x && y && theta);
    EXPECT_NEAR(*x, expected.x(), 0.02) << guess;
    EXPECT_NEAR(*y, expected.y(), 0.02) << guess;
    EXPECT_NEAR(*theta, expected.theta(), 0.005) << guess;
    EXPECT_TRUE(json_true(result.output, "converged")) << result.output;
    EXPECT_FALSE(json_true(result.output, "degenerate")) << result.output;
    const auto xx = json_number(result.output, "xx");
    ASSERT_TRUE(xx);
    EXPECT_GT(*xx, 0.0);
    EXPECT_LT(*xx, 1e-3);
    EXPECT_GT(json_number(result.output, "eigenvalue_ratio").value_or(0.0), 0.01);
  }
}

TEST_F(CovarianceCliTest, MatchInTheCorridorNamesItsAxisAsWeak) {
  const CommandResult result = run_command(slam2d("match --json " + corridor_log() + " --target 20 --source 30"));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  ASSERT_TRUE(JsonChecker(result.output).valid()) << result.output;
  EXPECT_TRUE(json_true(result.output, "degenerate")) << result.output;
  const std::size_t weak = result.output.find("\"weak_direction\"");
  ASSERT_NE(weak, std::string::npos);
  EXPECT_GT(std::abs(json_number(result.output.substr(weak), "x").value_or(0.0)), 0.9);
  EXPECT_GT(json_number(result.output, "xx").value_or(0.0), 100.0 * json_number(result.output, "yy").value_or(1.0));
}

TEST_F(CovarianceCliTest, MatchTextNamesTheResult) {
  const CommandResult result = run_command(slam2d("match " + room_log() + " --target 3 --source 4 --matcher icp"));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  for (const char* key : {"pose:", "converged:", "iterations:", "covariance:", "degenerate:", "eigenvalue_ratio:"}) {
    EXPECT_NE(result.output.find(key), std::string::npos) << key << "\n" << result.output;
  }
}

TEST_F(CovarianceCliTest, BadIndicesAndLogsFailClearly) {
  const CommandResult beyond = run_command(slam2d("match " + room_log() + " --target 0 --source 100000"));
  EXPECT_NE(beyond.exit_code, 0);
  EXPECT_NE(beyond.errors.find(room_log()), std::string::npos) << beyond.errors;
  EXPECT_NE(beyond.errors.find("out of range"), std::string::npos) << beyond.errors;
  const CommandResult same = run_command(slam2d("match " + room_log() + " --target 5 --source 5"));
  EXPECT_NE(same.exit_code, 0);
  EXPECT_NE(same.errors.find("different"), std::string::npos) << same.errors;
  const CommandResult negative = run_command(slam2d("match " + room_log() + " --target -1 --source 5"));
  EXPECT_NE(negative.exit_code, 0);
  const std::string missing = dir_->file("missing.clf");
  const CommandResult absent = run_command(slam2d("match " + missing + " --target 0 --source 1"));
  EXPECT_NE(absent.exit_code, 0);
  EXPECT_NE(absent.errors.find(missing), std::string::npos) << absent.errors;
  const CommandResult guess = run_command(slam2d("match " + room_log() + " --target 0 --source 1 --guess 1,2"));
  EXPECT_NE(guess.exit_code, 0);
  EXPECT_NE(guess.errors.find("--guess"), std::string::npos) << guess.errors;
  // A failed odometry run leaves no CSV behind.
  const std::string csv = dir_->file("none.csv");
  const CommandResult odometry = run_command(slam2d("odometry --quiet " + missing + " --out " + dir_->file("none.txt") +
                                                    " --covariance-csv " + csv));
  EXPECT_NE(odometry.exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(csv));
}

}  // namespace
}  // namespace slam2d
