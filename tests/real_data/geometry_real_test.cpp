// SPDX-License-Identifier: BSD-3-Clause
// The FLASER geometry check (docs/sensor_geometry.md) on every CARMEN log in $SLAM2D_DATA: each
// one gets a consistent 180 deg geometry without a warning, and a corrected log whose PARAM lines
// are rewritten in radians gives the same scans as the original.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/detail/number_format.hpp"
#include "slam2d/io/detail/text_input.hpp"
#include "real_data/real_logs.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<std::filesystem::path> carmen_logs(const std::filesystem::path& data) {
  std::vector<std::filesystem::path> logs;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(data)) {
    const std::string name = entry.path().filename().string();
    if (name.ends_with(".clf.gz") || name.ends_with("-corrected.log.gz")) logs.push_back(entry.path());
  }
  std::sort(logs.begin(), logs.end());
  return logs;
}

CarmenStats read_all(const std::string& path) {
  CarmenReader reader(path);
  while (reader.next()) {
  }
  return reader.stats();
}

TEST(GeometryRealData, EveryLogGetsAConsistent180DegreeGeometry) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<std::filesystem::path> logs = carmen_logs(data);
  ASSERT_EQ(logs.size(), 14u);  // README: 3 raw logs and 11 corrected ones
  char row[256];
  std::snprintf(row, sizeof(row), "%-32s %5s %6s %7s %7s %7s  %-22s %-22s %6s %-10s %8s\n", "log", "beams", "fov",
                "first", "step", "last", "fov from", "step from", "max m", "max from", "at max");
  std::cout << row;
  for (const auto& log : logs) {
    SCOPED_TRACE(log.string());
    const CarmenStats stats = read_all(log.string());
    ASSERT_FALSE(stats.old_laser_geometries.empty());
    for (const OldLaserGeometry& g : stats.old_laser_geometries) {
      const double steps = static_cast<double>(g.beams % 2 == 1 ? g.beams - 1 : g.beams);
      const double last = g.angle_min.value + static_cast<double>(g.beams - 1) * g.angle_increment.value;
      EXPECT_FALSE(g.rear);
      EXPECT_NEAR(g.field_of_view.value, kPi, 1e-12);
      EXPECT_NEAR(g.angle_min.value, -kPi / 2, 1e-12);
      EXPECT_NEAR(steps * g.angle_increment.value, kPi, 1e-12);  // 180/360 beams: n steps; 181/361: n - 1
      EXPECT_LE(last, kPi / 2 + 1e-12);
      EXPECT_NE(g.field_of_view.source, GeometrySource::kParamUnitGuess);
      EXPECT_TRUE(g.warnings.empty()) << g.warnings.front();
      EXPECT_EQ(g.scans, stats.laser_messages);
      std::snprintf(row, sizeof(row), "%-32s %5zu %6.1f %7.2f %7.3f %7.2f  %-22s %-22s %6.2f %-10s %7.2f%%\n",
                    log.filename().string().c_str(), g.beams, rad_to_deg(g.field_of_view.value),
                    rad_to_deg(g.angle_min.value), rad_to_deg(g.angle_increment.value), rad_to_deg(last),
                    to_string(g.field_of_view.source), to_string(g.angle_increment.source), g.range_max.value,
                    to_string(g.range_max.source),
                    100.0 * static_cast<double>(g.readings_at_range_max) / static_cast<double>(g.readings));
      std::cout << row;
    }
  }
}

// Copies `source` to `target` (plain text), replacing the line `from` by the lines `to`.
void rewrite(const std::string& source, const std::string& target, const std::string& from,
             const std::vector<std::string>& to) {
  LineReader reader(source);
  std::ofstream out(target);
  std::size_t replaced = 0;
  for (std::string line; reader.next(line);) {
    if (line.rfind(from, 0) == 0) {
      for (const std::string& replacement : to) out << replacement << "\n";
      ++replaced;
    } else {
      out << line << "\n";
    }
  }
  ASSERT_EQ(replaced, 1u) << from;
}

TEST(GeometryRealData, ParamsRewrittenInRadiansGiveTheSameScans) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  // Freiburg 101: "PARAM laser_front_laser_resolution 0.5 nohost 0", 360 beams.
  const std::string original = (data / "carmen-corrected/freiburg-101-corrected.log.gz").string();
  const std::string resolution_line = "PARAM laser_front_laser_resolution 0.5 ";
  test::TempDir dir;
  struct Variant {
    std::string name;
    std::vector<std::string> lines;
  };
  const std::vector<Variant> variants = {
      // The resolution in radians, printed exactly.
      {"resolution_radians.log", {"PARAM laser_front_laser_resolution " + format_number(deg_to_rad(0.5)) + " nohost 0"}},
      // The held-out log's pair: the field of view in radians (rounded as printed) next to the resolution in degrees.
      {"fov_radians.log", {"PARAM laser_front_laser_fov 3.14159 nohost 0", "PARAM laser_front_laser_resolution 0.5 nohost 0"}},
  };
  const std::vector<LaserMessage> expected = test::laser_messages(test::read_log(original));
  ASSERT_EQ(expected.size(), 292u);
  for (const Variant& variant : variants) {
    SCOPED_TRACE(variant.name);
    const std::string path = dir.file(variant.name);
    rewrite(original, path, resolution_line, variant.lines);
    const std::vector<LaserMessage> actual = test::laser_messages(test::read_log(path));
    ASSERT_EQ(actual.size(), expected.size());
    for (std::size_t i = 0; i < actual.size(); ++i) {
      const LaserScan& a = actual[i].scan;
      const LaserScan& b = expected[i].scan;
      ASSERT_NEAR(a.angle_min, b.angle_min, 1e-12) << i;
      ASSERT_NEAR(a.angle_increment, b.angle_increment, 1e-15) << i;
      ASSERT_NEAR(actual[i].field_of_view, expected[i].field_of_view, 1e-12) << i;
      ASSERT_EQ(a.range_max, b.range_max) << i;
      ASSERT_EQ(a.ranges, b.ranges) << i;
      ASSERT_EQ(a.stamp, b.stamp) << i;
      ASSERT_EQ(a.T_robot_sensor.vector(), b.T_robot_sensor.vector()) << i;
      ASSERT_EQ(actual[i].laser_pose.vector(), expected[i].laser_pose.vector()) << i;
    }
    const CarmenStats stats = read_all(path);
    ASSERT_EQ(stats.old_laser_geometries.size(), 1u);
    const OldLaserGeometry& g = stats.old_laser_geometries[0];
    EXPECT_EQ(variant.name == "fov_radians.log" ? g.field_of_view.source : g.angle_increment.source,
              GeometrySource::kParamUnitGuess);
    std::cout << variant.name << ": field of view " << g.field_of_view.reason << "; increment "
              << g.angle_increment.reason << "\n";
  }
}

}  // namespace
}  // namespace slam2d
