// SPDX-License-Identifier: BSD-3-Clause
// Trajectory files (slam2d text and TUM): hand-computed parse, exact round trips, malformed input.
#include "slam2d/io/trajectory_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::fixture_path;
using test::TempDir;
using test::expect_parse_error;

void expect_same(const Trajectory& actual, const Trajectory& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].stamp, expected[i].stamp) << i;
    EXPECT_EQ(actual[i].pose.x(), expected[i].pose.x()) << i;
    EXPECT_EQ(actual[i].pose.y(), expected[i].pose.y()) << i;
    EXPECT_EQ(actual[i].pose.theta(), expected[i].pose.theta()) << i;
  }
}

// Random poses over the whole angle range, plus the awkward angles.
Trajectory awkward_trajectory(std::size_t n) {
  Rng rng(11);
  Trajectory trajectory;
  for (std::size_t i = 0; i < n; ++i) {
    trajectory.push_back(1.7e9 + rng.uniform(0.0, 3000.0), SE2(rng.uniform(-100.0, 100.0), rng.gaussian(0.0, 1e-5),
                                                                rng.uniform(-std::numbers::pi, std::numbers::pi)));
  }
  for (double theta : {-std::numbers::pi, 0.0, -0.0, 1e-300, -1e-12, std::numbers::pi / 2.0, -std::numbers::pi / 2.0,
                       std::nextafter(std::numbers::pi, 0.0), 0.1, 1.0 / 3.0}) {
    trajectory.push_back(0.1, SE2(1.0 / 3.0, -2.5e-17, theta));
  }
  return trajectory;
}

TEST(TrajectoryIo, ReadsTextFixtureInFileOrder) {
  const Trajectory t = read_trajectory(fixture_path("trajectory/good.txt"));
  ASSERT_EQ(t.size(), 3u);
  expect_same(t, Trajectory({{10.0, SE2(1.0, 2.0, 0.5)}, {9.5, SE2(-1.0, 0.0, -1.25)}, {11.25, SE2(30.0, 0.125, 3.0)}}));
  EXPECT_EQ(t.backwards_steps(), 1u);  // kept as written, not sorted
}

TEST(TrajectoryIo, ReadsTumFixtureTakingYawFromTheQuaternion) {
  const Trajectory t = read_trajectory_tum(fixture_path("trajectory/good_tum.txt"));
  ASSERT_EQ(t.size(), 4u);
  EXPECT_EQ(t[0].stamp, 1.0);
  EXPECT_EQ(t[0].pose.theta(), 0.0);
  // (qz, qw) = (0.7071, 0.7071): 90 deg about z, whatever the rounding of the digits; tz is dropped.
  EXPECT_EQ(t[1].pose.x(), 1.0);
  EXPECT_EQ(t[1].pose.y(), 2.0);
  EXPECT_NEAR(t[1].pose.theta(), std::numbers::pi / 2.0, 1e-15);
  // (0, 1): 180 deg, which wraps to -pi.
  EXPECT_NEAR(std::abs(t[2].pose.theta()), std::numbers::pi, 1e-15);
  // -q is the same rotation as q: 90 deg again.
  EXPECT_NEAR(t[3].pose.theta(), std::numbers::pi / 2.0, 1e-15);
}

TEST(TrajectoryIo, TextWriteThenReadIsExact) {
  TempDir dir;
  const Trajectory trajectory = awkward_trajectory(300);
  for (const std::string name : {"t.txt", "t.txt.gz"}) {
    write_trajectory(dir.file(name), trajectory);
    expect_same(read_trajectory(dir.file(name)), trajectory);
  }
}

TEST(TrajectoryIo, TumWriteThenReadIsExact) {
  TempDir dir;
  const Trajectory trajectory = awkward_trajectory(3000);
  write_trajectory_tum(dir.file("t.tum"), trajectory);
  expect_same(read_trajectory_tum(dir.file("t.tum")), trajectory);
}

TEST(TrajectoryIo, TumWriterPutsTheRobotInThePlaneRotatedAboutZ) {
  TempDir dir;
  const double theta = 2.0;
  write_trajectory_tum(dir.file("t.tum"), Trajectory({{5.0, SE2(1.0, -1.0, theta)}}));
  std::ifstream in(dir.file("t.tum"));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.front(), '#');
  std::getline(in, line);
  std::istringstream fields(line);
  double stamp, tx, ty, tz, qx, qy, qz, qw;
  fields >> stamp >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
  EXPECT_EQ(stamp, 5.0);
  EXPECT_EQ(tx, 1.0);
  EXPECT_EQ(ty, -1.0);
  EXPECT_EQ(tz, 0.0);
  EXPECT_EQ(qx, 0.0);
  EXPECT_EQ(qy, 0.0);
  EXPECT_NEAR(qz, std::sin(theta / 2.0), 1e-15);
  EXPECT_NEAR(qw, std::cos(theta / 2.0), 1e-15);
}

TEST(TrajectoryIo, MalformedLinesGiveParseErrorWithPathAndLine) {
  expect_parse_error(read_trajectory, fixture_path("trajectory/short_line.txt"), 1, "expected 4 numbers, got 3");
  expect_parse_error(read_trajectory, fixture_path("trajectory/nan_theta.txt"), 2, "NaN in theta");
  expect_parse_error(read_trajectory, fixture_path("trajectory/bad_number.txt"), 3, "y is not a number: 'y'");
  expect_parse_error(read_trajectory_tum, fixture_path("trajectory/short_tum.txt"), 1, "expected 8 numbers, got 7");
  expect_parse_error(read_trajectory_tum, fixture_path("trajectory/non_unit_tum.txt"), 2, "not a unit quaternion");
  // A slam2d text trajectory is not a TUM file, nor the reverse.
  expect_parse_error(read_trajectory_tum, fixture_path("trajectory/good.txt"), 2, "expected 8 numbers, got 4");
  expect_parse_error(read_trajectory, fixture_path("trajectory/good_tum.txt"), 2, "expected 4 numbers, got 8");
}

TEST(TrajectoryIo, MissingFileGivesErrorNamingThePath) {
  const std::string path = fixture_path("trajectory/no_such_file.txt");
  for (auto read : {read_trajectory, read_trajectory_tum}) {
    try {
      read(path);
      ADD_FAILURE() << "no Error";
    } catch (const Error& e) {
      EXPECT_EQ(dynamic_cast<const ParseError*>(&e), nullptr);
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
}

TEST(TrajectoryIo, WritersRefuseNonFiniteValuesAndLeaveNoFile) {
  TempDir dir;
  const Trajectory bad({{1.0, SE2(0.0, 0.0, 0.0)}, {2.0, SE2(std::nan(""), 0.0, 0.0)}});
  EXPECT_THROW(write_trajectory(dir.file("a.txt"), bad), Error);
  EXPECT_THROW(write_trajectory_tum(dir.file("b.txt"), bad), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.txt")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("b.txt")));
}

}  // namespace
}  // namespace slam2d
