// SPDX-License-Identifier: BSD-3-Clause
// Tests for the CARMEN log reader and writer (src/slam2d/io/carmen_*.cpp) on the hand-written
// logs in tests/fixtures/carmen.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/carmen.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::fixture_path;

constexpr double kPi = std::numbers::pi;

std::string carmen_fixture(const std::string& name) { return fixture_path("carmen/" + name); }

struct ReadResult {
  std::vector<SensorMessage> messages;
  CarmenStats stats;
};

ReadResult read_log(const std::string& path, CarmenReaderOptions options = {}) {
  CarmenReader reader(path, options);
  ReadResult result;
  while (auto message = reader.next()) result.messages.push_back(std::move(*message));
  result.stats = reader.stats();
  return result;
}

const LaserMessage& laser(const ReadResult& result, std::size_t i) {
  return std::get<LaserMessage>(result.messages.at(i));
}

void write_messages(CarmenWriter& writer, const std::vector<SensorMessage>& messages) {
  for (const SensorMessage& message : messages) {
    writer.write(message);
  }
}

// The fixtures' ranges: range i = 0.5 + (i mod 10).
void expect_fixture_ranges(const LaserScan& scan, std::size_t n) {
  ASSERT_EQ(scan.ranges.size(), n);
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(scan.ranges[i], 0.5 + static_cast<double>(i % 10)) << i;
  EXPECT_TRUE(scan.intensities.empty());
}

void expect_pose_eq(const SE2& actual, double x, double y, double theta) {
  EXPECT_EQ(actual.x(), x);
  EXPECT_EQ(actual.y(), y);
  EXPECT_EQ(actual.theta(), normalize_angle(theta));
}

// ------------------------------------------------------------------------------------------------
// Message types.

TEST(CarmenReader, FlaserAnglesFollowTheCarmenConventionFor180181360361Beams) {
  const ReadResult log = read_log(carmen_fixture("flaser_beams.log"));
  ASSERT_EQ(log.messages.size(), 4u);
  struct Expected {
    std::size_t n;
    double increment_deg, last_deg;
  };
  const Expected expected[] = {{180, 1.0, 89.0}, {181, 1.0, 90.0}, {360, 0.5, 89.5}, {361, 0.5, 90.0}};
  for (std::size_t k = 0; k < 4; ++k) {
    const LaserMessage& m = laser(log, k);
    SCOPED_TRACE(m.scan.size());
    EXPECT_EQ(m.type, "FLASER");
    expect_fixture_ranges(m.scan, expected[k].n);
    EXPECT_DOUBLE_EQ(m.scan.angle_min, -kPi / 2);
    EXPECT_NEAR(m.scan.angle_increment, deg_to_rad(expected[k].increment_deg), 1e-15);
    EXPECT_NEAR(m.scan.angle_max(), deg_to_rad(expected[k].last_deg), 1e-12);
    EXPECT_DOUBLE_EQ(m.field_of_view, kPi);
    EXPECT_EQ(m.scan.range_min, 0.0);
    EXPECT_EQ(m.scan.range_max, 80.0);
    EXPECT_TRUE(m.scan.T_robot_sensor.is_approx(SE2(), 0.0));
    EXPECT_TRUE(m.has_poses);
    EXPECT_EQ(m.line, k + 2);
  }
  expect_pose_eq(laser(log, 0).laser_pose, 1, 2, 0.5);
  expect_pose_eq(laser(log, 0).odom_pose, 1.5, 2.5, 0.25);
  expect_pose_eq(laser(log, 3).laser_pose, 1.3, 2.3, 0.8);
  expect_pose_eq(laser(log, 3).odom_pose, 1.8, 2.8, 0.55);
  EXPECT_EQ(laser(log, 0).scan.stamp, 100.0);
  EXPECT_EQ(laser(log, 3).scan.stamp, 100.3);
  EXPECT_EQ(log.stats.laser_messages, 4u);
  EXPECT_EQ(log.stats.lines, 5u);
  EXPECT_EQ(log.stats.comment_lines, 1u);
}

TEST(CarmenReader, OdometryValuesAndTinyOrZeroStamps) {
  const ReadResult log = read_log(carmen_fixture("odom.log"));
  ASSERT_EQ(log.messages.size(), 4u);
  const auto& first = std::get<OdometryMessage>(log.messages[0]);
  expect_pose_eq(first.reading.pose, 1.5, -2.25, 0.75);
  EXPECT_EQ(first.reading.tv, 0.3);
  EXPECT_EQ(first.reading.rv, -0.1);
  EXPECT_EQ(first.reading.stamp, 1234.5);
  EXPECT_EQ(first.line, 2u);
  const auto& second = std::get<OdometryMessage>(log.messages[1]);
  EXPECT_NEAR(second.reading.pose.theta(), 4.0 - 2 * kPi, 1e-15);  // wrapped to [-pi, pi)
  EXPECT_EQ(second.reading.stamp, 1235.0);
  // The SLAM-corrected logs print stamps such as 3.44361e-86 and 0: finite, so accepted.
  EXPECT_EQ(std::get<OdometryMessage>(log.messages[2]).reading.stamp, 3.44361e-86);
  EXPECT_EQ(std::get<OdometryMessage>(log.messages[3]).reading.stamp, 0.0);
  EXPECT_EQ(log.stats.odometry_messages, 4u);
  EXPECT_EQ(log.stats.first_stamp, 1234.5);
  EXPECT_EQ(log.stats.last_stamp, 0.0);
  EXPECT_EQ(log.stats.backwards_timestamps, 2u);  // 1235 -> 3.4e-86 -> 0
  EXPECT_EQ(log.stats.backwards_laser_timestamps, 0u);
}

TEST(CarmenReader, TruePoses) {
  const ReadResult log = read_log(carmen_fixture("truepos.log"));
  ASSERT_EQ(log.messages.size(), 2u);
  const auto& first = std::get<TruePoseMessage>(log.messages[0]);
  expect_pose_eq(first.true_pose, 10.5, -3, 1.25);
  expect_pose_eq(first.odom_pose, 10, -2.5, 1);
  EXPECT_EQ(first.stamp, 55.5);
  EXPECT_EQ(first.line, 2u);
  const auto& second = std::get<TruePoseMessage>(log.messages[1]);
  expect_pose_eq(second.true_pose, 11, -3.5, -3);
  expect_pose_eq(second.odom_pose, 10.5, -3, -2.75);
  EXPECT_EQ(log.stats.true_pose_messages, 2u);
}

TEST(CarmenReader, ParamLinesOverrideGeometryForTheScansThatFollow) {
  const ReadResult log = read_log(carmen_fixture("params.log"));
  ASSERT_EQ(log.messages.size(), 4u);
  EXPECT_EQ(log.stats.param_messages, 8u);
  // Before any PARAM: the convention.
  const LaserMessage& plain = laser(log, 0);
  EXPECT_DOUBLE_EQ(plain.scan.angle_increment, kPi / 180);
  EXPECT_EQ(plain.scan.range_max, 80.0);
  EXPECT_TRUE(plain.scan.T_robot_sensor.is_approx(SE2(), 0.0));
  // laser_front_laser_fov 10 (deg): 11 beams -> 1 deg steps from -5 deg to +5 deg.
  const LaserMessage& odd = laser(log, 1);
  EXPECT_NEAR(odd.field_of_view, deg_to_rad(10), 1e-15);
  EXPECT_NEAR(odd.scan.angle_min, deg_to_rad(-5), 1e-15);
  EXPECT_NEAR(odd.scan.angle_increment, deg_to_rad(1), 1e-15);
  EXPECT_NEAR(odd.scan.angle_max(), deg_to_rad(5), 1e-14);
  EXPECT_EQ(odd.scan.range_max, 30.0);  // robot_front_laser_max
  expect_pose_eq(odd.scan.T_robot_sensor, 0.2, -0.05, 0.1);
  // 10 beams over 10 deg: 1 deg steps, last beam at +4 deg.
  const LaserMessage& even = laser(log, 2);
  EXPECT_NEAR(even.scan.angle_increment, deg_to_rad(1), 1e-15);
  EXPECT_NEAR(even.scan.angle_max(), deg_to_rad(4), 1e-14);
  // Later PARAM lines (fov 20, resolution 2 deg) decide again for the 11 beams: -10 .. +10 deg.
  const LaserMessage& wide = laser(log, 3);
  EXPECT_NEAR(wide.scan.angle_increment, deg_to_rad(2), 1e-15);
  EXPECT_NEAR(wide.scan.angle_min, deg_to_rad(-10), 1e-15);
  // One geometry per laser, beam count and PARAM set, in the order decided.
  const std::vector<OldLaserGeometry>& geometries = log.stats.old_laser_geometries;
  ASSERT_EQ(geometries.size(), 4u);
  const std::size_t beams[] = {180, 11, 10, 11};
  const std::size_t lines[] = {2, 9, 10, 13};
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(geometries[k].beams, beams[k]);
    EXPECT_EQ(geometries[k].first_line, lines[k]);
    EXPECT_EQ(geometries[k].scans, 1u);
    EXPECT_FALSE(geometries[k].rear);
    EXPECT_TRUE(geometries[k].warnings.empty()) << geometries[k].warnings.front();
  }
  EXPECT_EQ(geometries[0].field_of_view.source, GeometrySource::kConvention);
  EXPECT_EQ(geometries[1].field_of_view.source, GeometrySource::kParam);
  EXPECT_EQ(geometries[1].angle_increment.source, GeometrySource::kDerived);
  EXPECT_EQ(geometries[1].range_max.source, GeometrySource::kParam);
  EXPECT_EQ(geometries[3].angle_increment.source, GeometrySource::kParam);
}

TEST(CarmenReader, OptionsOverrideParamLinesAndDefaults) {
  CarmenReaderOptions options;
  options.geometry.field_of_view = kPi / 2;
  options.geometry.range_max = 12.5;
  options.range_min = 0.1;
  const ReadResult log = read_log(carmen_fixture("params.log"), options);
  ASSERT_EQ(log.messages.size(), 4u);
  EXPECT_DOUBLE_EQ(laser(log, 0).scan.angle_increment, kPi / 2 / 180);
  EXPECT_DOUBLE_EQ(laser(log, 0).scan.angle_min, -kPi / 4);
  EXPECT_DOUBLE_EQ(laser(log, 1).scan.angle_increment, kPi / 2 / 10);  // option beats PARAM fov
  // The PARAM resolution (2 deg) does not fit a 90 deg field of view over 11 beams: dropped, with a warning.
  EXPECT_DOUBLE_EQ(laser(log, 3).scan.angle_increment, kPi / 2 / 10);
  const OldLaserGeometry& late = log.stats.old_laser_geometries.at(3);
  EXPECT_EQ(late.field_of_view.source, GeometrySource::kOverride);
  EXPECT_EQ(late.angle_increment.source, GeometrySource::kDerived);
  ASSERT_EQ(late.warnings.size(), 1u);
  EXPECT_NE(late.warnings[0].find("laser_front_laser_resolution 2 (line 12)"), std::string::npos) << late.warnings[0];
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(laser(log, i).scan.range_max, 12.5);
    EXPECT_EQ(laser(log, i).scan.range_min, 0.1);
  }
  CarmenReaderOptions all;
  all.geometry.angle_increment = 0.01;
  all.geometry.angle_min = -0.3;
  all.default_range_max = 20.0;
  const ReadResult fixed = read_log(carmen_fixture("params.log"), all);
  EXPECT_EQ(laser(fixed, 0).scan.range_max, 20.0);  // no PARAM yet: the default
  EXPECT_EQ(laser(fixed, 1).scan.range_max, 30.0);  // PARAM beats the default
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(laser(fixed, i).scan.angle_increment, 0.01);
    EXPECT_EQ(laser(fixed, i).scan.angle_min, -0.3);
  }
}

// ------------------------------------------------------------------------------------------------
// The geometry check (docs/sensor_geometry.md).

// The one front geometry of a log read with `options`.
OldLaserGeometry front_geometry_of(const std::string& fixture, CarmenReaderOptions options = {}) {
  const ReadResult log = read_log(carmen_fixture(fixture), options);
  const OldLaserGeometry* geometry = log.stats.front_geometry();
  if (geometry == nullptr) throw Error(fixture + ": no front geometry");
  return *geometry;
}

void expect_angles_deg(const LaserScan& scan, double first_deg, double increment_deg, double last_deg) {
  EXPECT_NEAR(scan.angle_min, deg_to_rad(first_deg), 1e-12);
  EXPECT_NEAR(scan.angle_increment, deg_to_rad(increment_deg), 1e-12);
  EXPECT_NEAR(scan.angle_max(), deg_to_rad(last_deg), 1e-12);
}

TEST(CarmenGeometry, FieldOfViewInRadiansNextToAResolutionInDegreesIsRead) {
  // PARAM laser_front_laser_fov 3.14159 and laser_front_laser_resolution 0.5 with 361 beams:
  // in degrees 361 x 0.5 deg is not 3.14 deg; read as radians it is 180 deg. Before the check the
  // reader took 3.14 deg, starting the scan at -1.57 deg and turning every beam by about 88 deg.
  const ReadResult log = read_log(carmen_fixture("geometry_fov_radians.log"));
  ASSERT_EQ(log.messages.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const LaserMessage& m = laser(log, i);
    expect_fixture_ranges(m.scan, 361);
    expect_angles_deg(m.scan, -90.0, 0.5, 90.0);
    EXPECT_EQ(m.scan.angle_min, -kPi / 2);  // 3.14159 is pi as printed: exactly -pi/2
    EXPECT_EQ(m.field_of_view, kPi);
  }
  ASSERT_EQ(log.stats.old_laser_geometries.size(), 1u);  // decided once, at the first line
  const OldLaserGeometry& g = log.stats.old_laser_geometries[0];
  EXPECT_EQ(g.beams, 361u);
  EXPECT_EQ(g.scans, 2u);
  EXPECT_EQ(g.first_line, 4u);
  EXPECT_EQ(g.field_of_view.source, GeometrySource::kParamUnitGuess);
  EXPECT_NE(g.field_of_view.reason.find("laser_front_laser_fov 3.14159 (line 2) read as radians: 361 beams x 0.5 deg"),
            std::string::npos)
      << g.field_of_view.reason;
  EXPECT_EQ(g.angle_increment.source, GeometrySource::kParam);
  EXPECT_EQ(g.angle_min.source, GeometrySource::kDerived);
  EXPECT_EQ(g.range_max.source, GeometrySource::kConvention);
  EXPECT_TRUE(g.warnings.empty());
  EXPECT_STREQ(to_string(g.field_of_view.source), "PARAM (unit guessed)");
}

TEST(CarmenGeometry, FieldOfViewAndResolutionInDegreesAreKept) {
  const ReadResult log = read_log(carmen_fixture("geometry_fov_degrees.log"));
  ASSERT_EQ(log.messages.size(), 2u);
  expect_angles_deg(laser(log, 0).scan, -90.0, 0.5, 90.0);   // 361 beams: both ends
  expect_angles_deg(laser(log, 1).scan, -90.0, 0.5, 89.5);   // 360 beams: n steps
  ASSERT_EQ(log.stats.old_laser_geometries.size(), 2u);  // one per beam count
  for (const OldLaserGeometry& g : log.stats.old_laser_geometries) {
    EXPECT_EQ(g.field_of_view.source, GeometrySource::kParam);
    EXPECT_EQ(g.angle_increment.source, GeometrySource::kParam);
    EXPECT_NE(g.field_of_view.reason.find("in degrees"), std::string::npos) << g.field_of_view.reason;
    EXPECT_TRUE(g.warnings.empty());
  }
}

TEST(CarmenGeometry, A100DegreeScannerWith101BeamsIsCentred) {
  const ReadResult log = read_log(carmen_fixture("geometry_fov100.log"));
  ASSERT_EQ(log.messages.size(), 1u);
  expect_angles_deg(laser(log, 0).scan, -50.0, 1.0, 50.0);
  EXPECT_NEAR(laser(log, 0).field_of_view, deg_to_rad(100), 1e-15);
  EXPECT_EQ(laser(log, 0).scan.range_max, 5.0);
  const OldLaserGeometry& g = log.stats.old_laser_geometries.at(0);
  EXPECT_EQ(g.range_max.source, GeometrySource::kParam);
  // Ranges 0.5 + (i mod 10): 5.5 .. 9.5 are at or above the 5 m maximum, 5 of every 10.
  EXPECT_EQ(g.readings, 101u);
  EXPECT_EQ(g.readings_at_range_max, 50u);
}

TEST(CarmenGeometry, ContradictionNoUnitExplainsIsAParseErrorAtTheParamLine) {
  const std::string path = carmen_fixture("bad_geometry_contradiction.log");
  CarmenReader reader(path);
  ASSERT_TRUE(reader.next());  // the ODOM line
  try {
    reader.next();
    FAIL() << "no exception";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 3u);  // laser_front_laser_fov
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ":3: ", 0), 0u) << what;
    for (const char* part : {"laser_front_laser_fov 100 (line 3)", "laser_front_laser_resolution 0.25 (line 4)",
                             "181 beams", "180 deg", "override"}) {
      EXPECT_NE(what.find(part), std::string::npos) << part << " in " << what;
    }
  }
  // The overrides make the same log readable.
  CarmenReaderOptions options;
  options.geometry.field_of_view = deg_to_rad(45);
  options.geometry.angle_increment = deg_to_rad(0.25);
  const ReadResult log = read_log(path, options);
  ASSERT_EQ(log.messages.size(), 2u);
  expect_angles_deg(laser(log, 1).scan, -22.5, 0.25, 22.5);
  EXPECT_TRUE(log.stats.old_laser_geometries.at(0).warnings.empty());
}

TEST(CarmenGeometry, ContradictionTheConventionExplainsFallsBackWithAWarning) {
  // fov 180 fits 361 beams; a resolution of 1 deg does not (361 deg): the increment falls back
  // to the convention, 180 deg over 360 steps.
  const OldLaserGeometry g = front_geometry_of("geometry_fallback.log");
  EXPECT_NEAR(g.field_of_view.value, kPi, 1e-15);
  EXPECT_NEAR(g.angle_increment.value, deg_to_rad(0.5), 1e-15);
  EXPECT_NEAR(g.angle_min.value, -kPi / 2, 1e-15);
  EXPECT_EQ(g.angle_increment.source, GeometrySource::kDerived);
  ASSERT_EQ(g.warnings.size(), 1u);
  EXPECT_NE(g.warnings[0].find("laser_front_laser_resolution 1 (line 3)"), std::string::npos) << g.warnings[0];
  EXPECT_NE(g.warnings[0].find("convention"), std::string::npos) << g.warnings[0];
}

TEST(CarmenGeometry, OverridesBeatTheParamLines) {
  CarmenReaderOptions options;
  options.geometry.field_of_view = deg_to_rad(90);
  options.geometry.angle_increment = deg_to_rad(0.25);
  options.geometry.angle_min = deg_to_rad(-30);
  options.geometry.range_max = 7.5;
  const ReadResult log = read_log(carmen_fixture("geometry_fov_radians.log"), options);
  expect_angles_deg(laser(log, 0).scan, -30.0, 0.25, 60.0);
  EXPECT_EQ(laser(log, 0).scan.range_max, 7.5);
  EXPECT_NEAR(laser(log, 0).field_of_view, deg_to_rad(90), 1e-15);
  const OldLaserGeometry& g = log.stats.old_laser_geometries.at(0);
  for (const GeometryValue* v : {&g.field_of_view, &g.angle_min, &g.angle_increment, &g.range_max}) {
    EXPECT_EQ(v->source, GeometrySource::kOverride) << v->reason;
  }
  EXPECT_TRUE(g.warnings.empty());  // 361 x 0.25 deg fits 90 deg
  // A field of view override alone: the PARAM resolution (0.5 deg) fits 361 beams over 180 deg,
  // not 120 deg, so it is dropped with a warning and the increment is 120 deg / 360.
  CarmenReaderOptions fov_only;
  fov_only.geometry.field_of_view = deg_to_rad(120);
  const OldLaserGeometry h = front_geometry_of("geometry_fov_radians.log", fov_only);
  EXPECT_NEAR(h.angle_increment.value, deg_to_rad(120.0 / 360.0), 1e-15);
  EXPECT_NEAR(h.angle_min.value, deg_to_rad(-60), 1e-15);
  ASSERT_EQ(h.warnings.size(), 1u);
  EXPECT_NE(h.warnings[0].find("dropped"), std::string::npos) << h.warnings[0];
  // An increment override alone, against the radians fov: 361 x 0.5 deg fits 3.14159 read as radians.
  CarmenReaderOptions increment_only;
  increment_only.geometry.angle_increment = deg_to_rad(0.5);
  EXPECT_EQ(front_geometry_of("geometry_fov_radians.log", increment_only).field_of_view.source,
            GeometrySource::kParamUnitGuess);
}

TEST(CarmenGeometry, MisspelledFrontlaserResolutionIsAnAlias) {
  // FHW's "PARAM laser_frontlaser_resolution 1 0.0 nohost 0": taken as laser_front_laser_resolution,
  // and checked like it (180 beams x 1 deg fit the convention's 180 deg).
  const OldLaserGeometry g = front_geometry_of("geometry_alias.log");
  EXPECT_NEAR(g.angle_increment.value, deg_to_rad(1), 1e-15);
  EXPECT_EQ(g.angle_increment.source, GeometrySource::kParam);
  EXPECT_NE(g.angle_increment.reason.find("laser_frontlaser_resolution 1 (line 3, taken as laser_front_laser_resolution)"),
            std::string::npos)
      << g.angle_increment.reason;
  EXPECT_EQ(g.field_of_view.source, GeometrySource::kConvention);
  EXPECT_NEAR(g.angle_min.value, -kPi / 2, 1e-15);
}

// Logs written on the fly: PARAM lines, then one FLASER of `beams`.
class CarmenGeometryCases : public ::testing::Test {
 protected:
  OldLaserGeometry decide(const std::vector<std::string>& params, std::size_t beams) {
    const std::string path = dir_.file("case" + std::to_string(++count_) + ".log");
    std::ofstream out(path);
    for (const std::string& param : params) out << "PARAM " << param << " nohost 0\n";
    out << "FLASER " << beams;
    for (std::size_t i = 0; i < beams; ++i) out << " 1";
    out << " 0 0 0 0 0 0 1 host 1\n";
    out.close();
    const ReadResult log = read_log(path);
    return log.stats.old_laser_geometries.at(0);
  }
  test::TempDir dir_;
  int count_ = 0;
};

TEST_F(CarmenGeometryCases, ResolutionInRadiansIsGuessedOnlyWhenDegreesDoNotFit) {
  // 0.00872665 rad = 0.5 deg: 361 beams fit 180 deg only in radians.
  const OldLaserGeometry radians = decide({"laser_front_laser_resolution 0.00872665"}, 361);
  EXPECT_EQ(radians.angle_increment.source, GeometrySource::kParamUnitGuess);
  EXPECT_NEAR(radians.angle_increment.value, 0.00872665, 1e-15);
  EXPECT_NEAR(radians.field_of_view.value, kPi, 1e-15);
  // Both in radians fit together, as both in degrees do (a 3.14 deg scanner): the convention's 180 deg decides.
  const OldLaserGeometry both = decide({"laser_front_laser_fov 3.14159", "laser_front_laser_resolution 0.00872665"}, 361);
  EXPECT_EQ(both.field_of_view.source, GeometrySource::kParamUnitGuess);
  EXPECT_EQ(both.angle_increment.source, GeometrySource::kParamUnitGuess);
  EXPECT_NEAR(both.angle_min.value, -kPi / 2, 1e-5);
  // A field of view alone that is pi read as radians.
  const OldLaserGeometry fov_alone = decide({"laser_front_laser_fov 3.14159"}, 181);
  EXPECT_EQ(fov_alone.field_of_view.source, GeometrySource::kParamUnitGuess);
  EXPECT_EQ(fov_alone.field_of_view.value, kPi);
  EXPECT_NEAR(fov_alone.angle_increment.value, deg_to_rad(1), 1e-15);
  // Small values that fit in degrees stay degrees (a 5 deg scanner), with a warning as radians fit too.
  const OldLaserGeometry narrow = decide({"laser_front_laser_fov 5", "laser_front_laser_resolution 0.5"}, 11);
  EXPECT_EQ(narrow.field_of_view.source, GeometrySource::kParam);
  EXPECT_NEAR(narrow.field_of_view.value, deg_to_rad(5), 1e-15);
  EXPECT_EQ(narrow.warnings.size(), 1u);
  // A field of view of 3 alone, which is not 180 deg in radians: degrees, with a warning.
  const OldLaserGeometry three = decide({"laser_front_laser_fov 3"}, 181);
  EXPECT_EQ(three.field_of_view.source, GeometrySource::kParam);
  EXPECT_NEAR(three.field_of_view.value, deg_to_rad(3), 1e-15);
  EXPECT_EQ(three.warnings.size(), 1u);
}

TEST_F(CarmenGeometryCases, AResolutionThatDoesNotFit180DegreesSpansItsBeams) {
  // A 270 deg scanner (0.25 deg, 1081 beams) written as FLASER with its resolution only.
  const OldLaserGeometry wide = decide({"laser_front_laser_resolution 0.25"}, 1081);
  EXPECT_NEAR(wide.field_of_view.value, deg_to_rad(270), 1e-12);
  EXPECT_NEAR(wide.angle_min.value, deg_to_rad(-135), 1e-12);
  EXPECT_EQ(wide.field_of_view.source, GeometrySource::kDerived);
  EXPECT_EQ(wide.warnings.size(), 1u);  // not the convention's 180 deg
  // One that spans more than a full turn in any unit is an error at its line.
  EXPECT_THROW(decide({"laser_front_laser_resolution 3"}, 361), ParseError);
}

TEST_F(CarmenGeometryCases, AFieldOfViewOfMoreThanAFullTurnIsRefusedAtItsLine) {
  EXPECT_THROW(decide({"laser_front_laser_fov 400"}, 180), ParseError);
  EXPECT_NO_THROW(decide({"laser_front_laser_fov 360", "laser_front_laser_resolution 1"}, 360));
}

TEST(CarmenGeometry, OptionsOutOfRangeAreRefused) {
  const std::string path = carmen_fixture("flaser_beams.log");
  for (auto set : std::vector<void (*)(CarmenReaderOptions&)>{
           [](CarmenReaderOptions& o) { o.geometry.field_of_view = 0.0; },
           [](CarmenReaderOptions& o) { o.geometry.field_of_view = 7.0; },
           [](CarmenReaderOptions& o) { o.geometry.angle_increment = -0.01; },
           [](CarmenReaderOptions& o) { o.geometry.angle_min = std::numeric_limits<double>::quiet_NaN(); },
           [](CarmenReaderOptions& o) { o.geometry.range_max = 0.0; }}) {
    CarmenReaderOptions options;
    set(options);
    EXPECT_THROW({ CarmenReader reader(path, options); }, Error);
  }
}

TEST(CarmenReader, RearLaserFacesBackwardsWithTheRearParams) {
  const ReadResult log = read_log(carmen_fixture("rlaser.log"));
  ASSERT_EQ(log.messages.size(), 2u);
  const LaserMessage& rear = laser(log, 0);
  EXPECT_EQ(rear.type, "RLASER");
  expect_fixture_ranges(rear.scan, 181);
  EXPECT_NEAR(rear.field_of_view, kPi / 2, 1e-15);  // laser_rear_laser_fov 90
  EXPECT_NEAR(rear.scan.angle_increment, deg_to_rad(0.5), 1e-15);
  EXPECT_NEAR(rear.scan.angle_min, -kPi / 4, 1e-15);
  EXPECT_EQ(rear.scan.range_max, 40.0);
  EXPECT_TRUE(test::poses_near(rear.scan.T_robot_sensor, SE2(-0.3, 0.1, 0.2 + kPi), 0.0, 1e-15));
  // Beam 90 looks along the sensor's x axis; its end point lies behind the robot.
  const ScanPoints points = to_point_cloud(rear.scan, ScanFrame::kRobot);
  const std::size_t k = std::find(points.beam_indices.begin(), points.beam_indices.end(), 90u) -
                        points.beam_indices.begin();
  ASSERT_LT(k, points.beam_indices.size());
  EXPECT_NEAR(points.cloud.points[k].x(), -0.3 - 0.5 * std::cos(0.2), 1e-12);
  EXPECT_NEAR(points.cloud.points[k].y(), 0.1 - 0.5 * std::sin(0.2), 1e-12);
  // The front laser keeps the front defaults.
  const LaserMessage& front = laser(log, 1);
  EXPECT_TRUE(front.scan.T_robot_sensor.is_approx(SE2(), 0.0));
  EXPECT_EQ(front.scan.range_max, 80.0);
  EXPECT_DOUBLE_EQ(front.field_of_view, kPi);
}

TEST(CarmenReader, RobotLaserGeometryComesFromItsPoses) {
  const ReadResult log = read_log(carmen_fixture("robotlaser1.log"));
  ASSERT_EQ(log.messages.size(), 2u);
  const LaserMessage& m = laser(log, 0);
  EXPECT_EQ(m.type, "ROBOTLASER1");
  EXPECT_EQ(m.scan.angle_min, -1.5);
  EXPECT_EQ(m.field_of_view, 3.0);
  EXPECT_EQ(m.scan.angle_increment, 0.75);
  EXPECT_EQ(m.scan.range_max, 50.0);
  EXPECT_EQ(m.scan.ranges, (std::vector<double>{1, 2, 3, 4, 50}));
  EXPECT_TRUE(m.scan.intensities.empty());
  EXPECT_FALSE(m.scan.is_valid(4));  // at maximum_range: no return
  EXPECT_TRUE(m.scan.is_valid(3));
  expect_pose_eq(m.laser_pose, 2, 1.25, kPi / 2);
  expect_pose_eq(m.odom_pose, 2, 1, kPi / 2);
  // Laser 0.25 m ahead of a robot facing +y: T_robot_sensor = (0.25, 0, 0).
  EXPECT_TRUE(test::poses_near(m.scan.T_robot_sensor, SE2(0.25, 0, 0), 1e-12, 1e-12));
  EXPECT_EQ(m.scan.stamp, 7.5);
  EXPECT_TRUE(m.has_poses);
  const LaserMessage& with_remissions = laser(log, 1);
  EXPECT_EQ(with_remissions.scan.ranges, (std::vector<double>{1.5, 2.5, 3.5, 4.5, 5.5}));
  EXPECT_EQ(with_remissions.scan.intensities, (std::vector<double>{10, 20, 30, 40, 50}));
  EXPECT_EQ(with_remissions.scan.angle_min, -0.5);
  EXPECT_EQ(with_remissions.scan.range_max, 8.0);
  EXPECT_TRUE(with_remissions.scan.T_robot_sensor.is_approx(SE2(), 0.0));
}

TEST(CarmenReader, RawLasersCarryNoPose) {
  const ReadResult log = read_log(carmen_fixture("rawlaser.log"));
  ASSERT_EQ(log.messages.size(), 4u);
  const char* types[] = {"RAWLASER1", "RAWLASER2", "RAWLASER3", "RAWLASER4"};
  const double stamps[] = {9, 9.5, 10, 10.5};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(laser(log, i).type, types[i]);
    EXPECT_FALSE(laser(log, i).has_poses);
    EXPECT_EQ(laser(log, i).scan.stamp, stamps[i]);
  }
  const LaserMessage& first = laser(log, 0);
  EXPECT_EQ(first.scan.angle_min, -kPi / 2);
  EXPECT_EQ(first.scan.angle_increment, kPi / 4);
  EXPECT_EQ(first.field_of_view, kPi);
  EXPECT_EQ(first.scan.range_max, 81.9);
  EXPECT_EQ(first.scan.ranges, (std::vector<double>{1, 2, 3, 4, 5}));
  EXPECT_EQ(laser(log, 1).scan.intensities, (std::vector<double>{100, 200, 300}));
  EXPECT_EQ(laser(log, 3).scan.ranges, (std::vector<double>{2, 2}));
}

TEST(CarmenReader, MissingHostnameAndLoggerTimestampAreAccepted) {
  const ReadResult log = read_log(carmen_fixture("short_tail.log"));
  ASSERT_EQ(log.messages.size(), 4u);
  EXPECT_EQ(laser(log, 0).scan.stamp, 42.5);
  EXPECT_EQ(laser(log, 1).scan.stamp, 43.5);
  const auto& odometry = std::get<OdometryMessage>(log.messages[2]);
  EXPECT_EQ(odometry.reading.stamp, 44.0);
  EXPECT_EQ(odometry.reading.tv, 0.5);
  EXPECT_EQ(odometry.reading.rv, 0.25);
  EXPECT_EQ(std::get<TruePoseMessage>(log.messages[3]).stamp, 45.0);
}

TEST(CarmenReader, CommentsBlankLinesAndUnknownTypesAreCounted) {
  const ReadResult log = read_log(carmen_fixture("unknown_types.log"));
  ASSERT_EQ(log.messages.size(), 4u);
  EXPECT_EQ(std::get<OdometryMessage>(log.messages[0]).line, 5u);
  EXPECT_EQ(laser(log, 1).line, 6u);
  EXPECT_EQ(laser(log, 2).line, 9u);
  EXPECT_EQ(std::get<OdometryMessage>(log.messages[3]).line, 13u);
  const CarmenStats& s = log.stats;
  EXPECT_EQ(s.lines, 13u);
  EXPECT_EQ(s.comment_lines, 5u);
  EXPECT_EQ(s.laser_messages, 2u);
  EXPECT_EQ(s.odometry_messages, 2u);
  EXPECT_EQ(s.param_messages, 0u);
  EXPECT_EQ(s.skipped_lines, 4u);
  const std::map<std::string, std::size_t> skipped{{"NEFF", 2}, {"SYNC", 1}, {"GPSNMEAGGA", 1}};
  EXPECT_EQ(s.skipped_types, skipped);
}

TEST(CarmenReader, BackwardsTimestampsAreKeptAndCountedOverAllMessagesAndOverLasers) {
  const ReadResult log = read_log(carmen_fixture("backwards.log"));
  ASSERT_EQ(log.messages.size(), 7u);
  EXPECT_EQ(laser(log, 1).scan.stamp, 9.0);  // kept in file order
  EXPECT_EQ(log.stats.backwards_timestamps, 3u);  // 10 > 9, 11 > 10.5, 10.5 > 10 (10 == 10 is not back)
  EXPECT_EQ(log.stats.backwards_laser_timestamps, 1u);  // 10.5 > 10
  EXPECT_EQ(log.stats.first_stamp, 10.0);
  EXPECT_EQ(log.stats.last_stamp, 12.0);  // the PARAM stamp (1) does not count
  EXPECT_EQ(log.stats.param_messages, 1u);
  EXPECT_EQ(log.stats.true_pose_messages, 1u);
}

TEST(CarmenReader, EmptyFileHasNoMessagesAndNoStamps) {
  test::TempDir dir;
  std::ofstream(dir.file("empty.log")).close();
  const ReadResult log = read_log(dir.file("empty.log"));
  EXPECT_TRUE(log.messages.empty());
  EXPECT_EQ(log.stats.lines, 0u);
  EXPECT_FALSE(log.stats.first_stamp.has_value());
  EXPECT_FALSE(log.stats.last_stamp.has_value());
}

TEST(CarmenReader, ProgressGoesFromZeroToOneForPlainAndGzipFiles) {
  test::TempDir dir;
  const ReadResult original = read_log(carmen_fixture("flaser_beams.log"));
  for (const std::string name : {"progress.log", "progress.log.gz"}) {
    CarmenWriter writer(dir.file(name));
    write_messages(writer, original.messages);
    writer.commit();
    CarmenReader reader(dir.file(name));
    EXPECT_EQ(reader.progress(), 0.0);
    ASSERT_TRUE(reader.next());
    ASSERT_TRUE(reader.next());
    const double half = reader.progress();
    EXPECT_GT(half, 0.2) << name;  // the 181-beam line of four is about half of the bytes
    EXPECT_LT(half, 0.5) << name;
    while (reader.next()) {
    }
    EXPECT_EQ(reader.progress(), 1.0) << name;
  }
}

// ------------------------------------------------------------------------------------------------
// Errors.

// The Error `open` throws for `path` names the path.
template <typename Open>
void expect_error_naming(const std::string& path, Open open) {
  try {
    open();
    FAIL() << "no exception for " << path;
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
  }
}

TEST(CarmenReader, MissingFileGivesAnErrorNamingThePath) {
  const std::string path = "/nonexistent/slam2d/no-such-log.clf";
  expect_error_naming(path, [&] { CarmenReader reader(path); });
}

struct MalformedCase {
  const char* file;
  std::size_t line;
  const char* message;  // must appear in what() after "PATH:LINE: "
};

void PrintTo(const MalformedCase& c, std::ostream* os) { *os << c.file; }

class CarmenMalformed : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(CarmenMalformed, GivesParseErrorWithPathLineAndProblem) {
  const MalformedCase& c = GetParam();
  const std::string path = carmen_fixture(c.file);
  CarmenReader reader(path);
  std::size_t good = 0;
  try {
    while (reader.next()) ++good;
    FAIL() << "no exception for " << c.file;
  } catch (const ParseError& e) {
    const std::string what = e.what();
    const std::string prefix = path + ":" + std::to_string(c.line) + ": ";
    EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
    EXPECT_NE(what.find(c.message), std::string::npos) << what;
    EXPECT_EQ(e.path(), path);
    EXPECT_EQ(e.line(), c.line);
  }
  EXPECT_EQ(good, c.line - 2);  // every line before the bad one is a good ODOM after one comment
}

INSTANTIATE_TEST_SUITE_P(
    Fixtures, CarmenMalformed,
    ::testing::Values(
        MalformedCase{"bad_truncated_flaser.log", 3, "FLASER: expected 180 ranges + 9 fields, got 95 tokens"},
        MalformedCase{"bad_nan_range.log", 3, "FLASER: range 3 of 5 is NaN"},
        MalformedCase{"bad_negative_range.log", 3, "FLASER: range 2 of 5 is negative: -1.5"},
        MalformedCase{"bad_inf_range.log", 3, "FLASER: range 4 of 5 is infinite"},
        MalformedCase{"bad_garbage_token.log", 3, "FLASER: range 1 of 5 is not a number: '1.2x'"},
        MalformedCase{"bad_wrong_count.log", 3,
                      "ODOM: expected 9 fields (x y theta tv rv accel ipc_timestamp ipc_hostname "
                      "logger_timestamp), got 11 tokens"},
        MalformedCase{"bad_nan_pose.log", 3, "FLASER: x is NaN"},
        MalformedCase{"bad_inf_stamp.log", 5, "ODOM: ipc_timestamp is infinite"},
        MalformedCase{"bad_garbage_stamp.log", 3, "TRUEPOS: ipc_timestamp is not a number: '12.5abc'"},
        MalformedCase{"bad_num_readings.log", 3, "FLASER: num_readings is not a count: 'abc'"},
        MalformedCase{"bad_remissions.log", 3, "ROBOTLASER1: 3 remissions for 5 ranges"},
        MalformedCase{"bad_robotlaser_truncated.log", 3, "ROBOTLASER1: expected 5 ranges"},
        MalformedCase{"bad_param_value.log", 3, "PARAM: robot_front_laser_max value is not a number: 'abc'"},
        MalformedCase{"bad_param_fov.log", 3, "PARAM: laser_front_laser_fov must be positive, got -10"},
        MalformedCase{"bad_geometry_contradiction.log", 3, "do not fit 181 beams in any unit"},
        MalformedCase{"bad_rawlaser_max_range.log", 3, "RAWLASER1: maximum_range must be positive, got 0"}),
    [](const ::testing::TestParamInfo<MalformedCase>& info) {
      std::string name = info.param.file;
      name = name.substr(0, name.find('.'));
      return name;
    });

// Mutated copies of good lines either parse to finite, non-negative values or give a ParseError
// naming the line: never a crash, never another exception, never a NaN let through.
TEST(CarmenReader, MutatedLinesGiveParseErrorsOrCleanMessages) {
  std::vector<std::string> lines;
  for (const char* name : {"rawlaser.log", "robotlaser1.log", "short_tail.log", "params.log", "odom.log"}) {
    std::ifstream in(carmen_fixture(name));
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line[0] != '#') lines.push_back(line);
    }
  }
  const std::vector<std::string> garbage = {"nan", "-1", "1e999", "abc", "0x10", "+", "-", "1e", ".", "inf",
                                            "99999999999999999999", "-0", "1.5.5", "--1", "+-1", "\t"};
  std::mt19937_64 rng(20240611);
  test::TempDir dir;
  std::size_t errors = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const std::string path = dir.file("mutated" + std::to_string(trial) + ".log");  // O_TRUNC is slow here
    std::vector<std::string> tokens;
    std::istringstream split(lines[rng() % lines.size()]);
    for (std::string token; split >> token;) tokens.push_back(token);
    const std::size_t k = 1 + rng() % (tokens.size() - 1);
    switch (rng() % 3) {
      case 0: tokens.erase(tokens.begin() + static_cast<std::ptrdiff_t>(k)); break;
      case 1: tokens.insert(tokens.begin() + static_cast<std::ptrdiff_t>(k), tokens[k]); break;
      default: tokens[k] = garbage[rng() % garbage.size()]; break;
    }
    std::string line = tokens[0];
    for (std::size_t i = 1; i < tokens.size(); ++i) line += " " + tokens[i];
    std::ofstream(path) << line << "\n";
    try {
      for (const SensorMessage& message : read_log(path).messages) {
        if (const auto* laser = std::get_if<LaserMessage>(&message)) {
          for (double r : laser->scan.ranges) EXPECT_TRUE(std::isfinite(r) && r >= 0.0) << line;
          EXPECT_TRUE(std::isfinite(laser->scan.stamp)) << line;
          EXPECT_TRUE(laser->odom_pose.vector().allFinite()) << line;
        }
      }
    } catch (const ParseError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ":1: ", 0), 0u) << e.what();
      ++errors;
    }
  }
  EXPECT_GT(errors, 100u);  // most mutations break the line
}

// ------------------------------------------------------------------------------------------------
// Writer.

void expect_same_message(const SensorMessage& a, const SensorMessage& b) {
  ASSERT_EQ(a.index(), b.index());
  if (const auto* x = std::get_if<LaserMessage>(&a)) {
    const auto& y = std::get<LaserMessage>(b);
    EXPECT_EQ(x->type, y.type);
    EXPECT_EQ(x->field_of_view, y.field_of_view);
    EXPECT_EQ(x->laser_pose.vector(), y.laser_pose.vector());
    EXPECT_EQ(x->odom_pose.vector(), y.odom_pose.vector());
    EXPECT_EQ(x->has_poses, y.has_poses);
    EXPECT_EQ(x->scan.stamp, y.scan.stamp);
    EXPECT_EQ(x->scan.angle_min, y.scan.angle_min);
    EXPECT_EQ(x->scan.angle_increment, y.scan.angle_increment);
    EXPECT_EQ(x->scan.range_min, y.scan.range_min);
    EXPECT_EQ(x->scan.range_max, y.scan.range_max);
    EXPECT_EQ(x->scan.ranges, y.scan.ranges);
    EXPECT_EQ(x->scan.intensities, y.scan.intensities);
    EXPECT_EQ(x->scan.T_robot_sensor.vector(), y.scan.T_robot_sensor.vector());
  } else if (const auto* o = std::get_if<OdometryMessage>(&a)) {
    const auto& p = std::get<OdometryMessage>(b);
    EXPECT_EQ(o->reading.stamp, p.reading.stamp);
    EXPECT_EQ(o->reading.pose.vector(), p.reading.pose.vector());
    EXPECT_EQ(o->reading.tv, p.reading.tv);
    EXPECT_EQ(o->reading.rv, p.reading.rv);
  } else {
    const auto& t = std::get<TruePoseMessage>(a);
    const auto& u = std::get<TruePoseMessage>(b);
    EXPECT_EQ(t.stamp, u.stamp);
    EXPECT_EQ(t.true_pose.vector(), u.true_pose.vector());
    EXPECT_EQ(t.odom_pose.vector(), u.odom_pose.vector());
  }
}

class CarmenRoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(CarmenRoundTrip, FixtureWrittenPlainAndGzipReadsBackIdentically) {
  const ReadResult original = read_log(carmen_fixture(GetParam()));
  ASSERT_FALSE(original.messages.empty());
  test::TempDir dir;
  for (const std::string name : {"out.log", "out.log.gz"}) {
    SCOPED_TRACE(name);
    const std::string path = dir.file(name);
    CarmenWriter writer(path);
    writer.write_comment("round trip of " + std::string(GetParam()));
    write_messages(writer, original.messages);
    writer.commit();
    const ReadResult copy = read_log(path);
    ASSERT_EQ(copy.messages.size(), original.messages.size());
    for (std::size_t i = 0; i < copy.messages.size(); ++i) expect_same_message(copy.messages[i], original.messages[i]);
    EXPECT_EQ(copy.stats.backwards_timestamps, original.stats.backwards_timestamps);
    EXPECT_EQ(copy.stats.comment_lines, 1u);
  }
  // The .gz file really is compressed (gzip magic bytes).
  std::ifstream gz(dir.file("out.log.gz"), std::ios::binary);
  unsigned char magic[2] = {0, 0};
  gz.read(reinterpret_cast<char*>(magic), 2);
  EXPECT_EQ(magic[0], 0x1f);
  EXPECT_EQ(magic[1], 0x8b);
}

INSTANTIATE_TEST_SUITE_P(Fixtures, CarmenRoundTrip,
                         ::testing::Values("flaser_beams.log", "odom.log", "truepos.log", "robotlaser1.log",
                                           "rawlaser.log", "short_tail.log", "unknown_types.log", "backwards.log"));

// Awkward doubles: every one must come back bit for bit.
std::vector<SensorMessage> awkward_messages() {
  LaserMessage front;
  front.type = "FLASER";
  front.scan.stamp = 976052857.337284;
  front.scan.ranges = {1.0 / 3.0, 0.1 + 0.2, 81.91, 0.0, 1e-300, 5e-324, 123456789.123456789};
  front.laser_pose = SE2(-1e-17, 1e22, kPi - 1e-12);
  front.odom_pose = SE2(0.1, -0.2, -kPi);
  LaserMessage robot;
  robot.type = "ROBOTLASER1";
  robot.scan.stamp = 3.44361e-86;
  robot.scan.angle_min = -2.0943951023931953;
  robot.scan.angle_increment = 0.006135923151542565;
  robot.field_of_view = 4.1887902047863905;
  robot.scan.range_max = 5.6;
  robot.scan.ranges = {0.02, 5.599999999999999, 2.0 / 3.0};
  robot.scan.intensities = {-1.5, 0.0, 1e10};
  robot.laser_pose = SE2(1.0 / 7.0, 2.0 / 7.0, 3.0 / 7.0);
  robot.odom_pose = SE2(1.0 / 11.0, 2.0 / 11.0, 3.0 / 11.0);
  LaserMessage raw = robot;
  raw.type = "RAWLASER3";
  raw.has_poses = false;
  raw.laser_pose = SE2();
  raw.odom_pose = SE2();
  raw.scan.intensities.clear();
  OdometryMessage odometry;
  odometry.reading = {.stamp = 0.1 + 0.7, .pose = SE2(1e-5 / 3.0, -7.0 / 9.0, 2.5), .tv = -0.3, .rv = 1.0 / 3.0};
  TruePoseMessage truth;
  truth.stamp = -0.0;
  truth.true_pose = SE2(std::numeric_limits<double>::max(), std::numeric_limits<double>::min(), 1e-300);
  truth.odom_pose = SE2(-3.5, 0.0, -1.0);
  return {front, robot, raw, odometry, truth};
}

TEST(CarmenWriter, AwkwardNumbersRoundTripExactlyPlainAndGzip) {
  std::vector<SensorMessage> messages = awkward_messages();
  test::TempDir dir;
  for (const std::string name : {"awkward.clf", "awkward.clf.gz"}) {
    SCOPED_TRACE(name);
    CarmenWriter writer(dir.file(name));
    write_messages(writer, messages);
    writer.commit();
    const ReadResult copy = read_log(dir.file(name));
    ASSERT_EQ(copy.messages.size(), messages.size());
    // The reader fills what the file does not carry: FLASER geometry (the convention) and the
    // ROBOTLASER1 mounting (from its two poses); set those on the originals to compare.
    auto& front = std::get<LaserMessage>(messages[0]);
    front.field_of_view = kPi;
    front.scan.angle_min = -kPi / 2;
    front.scan.angle_increment = kPi / 6;  // 7 beams, odd: fov / (n - 1)
    front.scan.range_max = 80.0;
    auto& robot = std::get<LaserMessage>(messages[1]);
    robot.scan.T_robot_sensor = robot.odom_pose.between(robot.laser_pose);
    for (std::size_t i = 0; i < messages.size(); ++i) expect_same_message(copy.messages[i], messages[i]);
    EXPECT_TRUE(std::signbit(std::get<TruePoseMessage>(copy.messages[4]).stamp));  // -0 stays -0
  }
}

TEST(CarmenWriter, ParamLinesCarryTheOldLaserGeometry) {
  test::TempDir dir;
  const std::string path = dir.file("params.log");
  const ReadResult original = read_log(carmen_fixture("rlaser.log"));
  {
    CarmenWriter writer(path);
    writer.write_comment("rear laser geometry\nas PARAM lines");
    writer.write_param("robot_rearlaser_offset", "-0.3", 0.0);
    writer.write_param("robot_rearlaser_side_offset", "0.1", 0.0);
    writer.write_param("robot_rearlaser_angular_offset", "0.2", 0.0);
    writer.write_param("robot_rear_laser_max", "40", 0.0);
    writer.write_param("laser_rear_laser_fov", "90", 0.0);
    write_messages(writer, original.messages);
    writer.commit();
  }
  const ReadResult copy = read_log(path);
  EXPECT_EQ(copy.stats.param_messages, 5u);
  EXPECT_EQ(copy.stats.comment_lines, 2u);
  ASSERT_EQ(copy.messages.size(), original.messages.size());
  for (std::size_t i = 0; i < copy.messages.size(); ++i) expect_same_message(copy.messages[i], original.messages[i]);
}

TEST(CarmenWriter, NothingAppearsUntilCommitAndAFailedWriterLeavesNoFile) {
  test::TempDir dir;
  const std::string path = dir.file("never.log.gz");
  {
    CarmenWriter writer(path);
    write_messages(writer, awkward_messages());
    EXPECT_FALSE(std::filesystem::exists(path));
  }  // destroyed without commit
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));  // no temporary left behind
  {
    CarmenWriter writer(path);
    LaserMessage bad;
    bad.type = "FLASER";
    bad.scan.ranges = {1.0, std::numeric_limits<double>::quiet_NaN()};
    EXPECT_THROW(writer.write(bad), Error);
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(CarmenWriter, RefusesWhatCannotBeReadBack) {
  test::TempDir dir;
  CarmenWriter writer(dir.file("refused.log"));
  LaserMessage negative;
  negative.type = "FLASER";
  negative.scan.ranges = {1.0, -0.5};
  EXPECT_THROW(writer.write(negative), Error);
  LaserMessage unknown;
  unknown.type = "LASER5";
  EXPECT_THROW(writer.write(unknown), Error);
  LaserMessage no_poses;
  no_poses.type = "FLASER";
  no_poses.has_poses = false;
  EXPECT_THROW(writer.write(no_poses), Error);
  LaserMessage mismatch;
  mismatch.type = "ROBOTLASER1";
  mismatch.scan.range_max = 10.0;
  mismatch.scan.ranges = {1.0, 2.0};
  mismatch.scan.intensities = {1.0};
  EXPECT_THROW(writer.write(mismatch), Error);
  OdometryMessage odometry;
  odometry.reading.stamp = std::numeric_limits<double>::infinity();
  EXPECT_THROW(writer.write(odometry), Error);
  EXPECT_THROW(writer.write_param("two words", "1", 0.0), Error);
  EXPECT_THROW(writer.write_param("name", "", 0.0), Error);
  // After the refusals the file holds only what was accepted.
  odometry.reading.stamp = 1.0;
  writer.write(odometry);
  writer.commit();
  EXPECT_THROW(writer.write(odometry), Error);  // after commit
  const ReadResult copy = read_log(dir.file("refused.log"));
  EXPECT_EQ(copy.messages.size(), 1u);
  EXPECT_EQ(copy.stats.lines, 1u);
}

TEST(CarmenWriter, UnwritableDirectoryGivesAnErrorNamingThePath) {
  const std::string path = "/nonexistent/slam2d/out.clf";
  expect_error_naming(path, [&] { CarmenWriter writer(path); });
}

TEST(CarmenWriter, WritesTheDocumentedLineFormats) {
  test::TempDir dir;
  const std::string path = dir.file("format.log");
  CarmenWriter writer(path);
  const ReadResult fixture = read_log(carmen_fixture("short_tail.log"));
  writer.write(laser(fixture, 0));
  writer.write(std::get<OdometryMessage>(fixture.messages[2]));
  writer.write_param("robot_front_laser_max", "30", 2.5);
  writer.commit();
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "FLASER 5 0.5 1.5 2.5 3.5 4.5 1 2 3 1 2 3 42.5 slam2d 42.5");
  std::getline(in, line);
  EXPECT_EQ(line, "ODOM 1 2 3 0.5 0.25 0 44 slam2d 44");
  std::getline(in, line);
  EXPECT_EQ(line, "PARAM robot_front_laser_max 30 2.5 slam2d 2.5");
}

}  // namespace
}  // namespace slam2d
