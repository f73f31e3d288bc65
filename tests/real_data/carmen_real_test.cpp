// SPDX-License-Identifier: BSD-3-Clause
// The CARMEN reader on the real logs in $SLAM2D_DATA: message counts, beams and durations from
// $SLAM2D_DATA/README.md, Intel's backwards timestamps, exact write -> read of a whole log.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/io/carmen.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

struct LogSummary {
  std::size_t lasers = 0;
  std::size_t odometry = 0;
  std::map<std::size_t, std::size_t> beams;  // beam count -> scans
  std::optional<double> first_laser_stamp;   // s
  std::optional<double> last_laser_stamp;    // s
  double largest_range = 0.0;                // m
  CarmenStats stats;
  double milliseconds = 0.0;

  double laser_duration() const { return *last_laser_stamp - *first_laser_stamp; }
};

LogSummary summarize(const std::filesystem::path& path) {
  const auto start = std::chrono::steady_clock::now();
  CarmenReader reader(path.string());
  LogSummary summary;
  while (auto message = reader.next()) {
    if (const auto* laser = std::get_if<LaserMessage>(&*message)) {
      ++summary.lasers;
      ++summary.beams[laser->scan.size()];
      if (!summary.first_laser_stamp) summary.first_laser_stamp = laser->scan.stamp;
      summary.last_laser_stamp = laser->scan.stamp;
      for (double r : laser->scan.ranges) summary.largest_range = std::max(summary.largest_range, r);
    } else if (std::holds_alternative<OdometryMessage>(*message)) {
      ++summary.odometry;
    }
  }
  summary.stats = reader.stats();
  const std::chrono::duration<double, std::milli> elapsed = std::chrono::steady_clock::now() - start;
  summary.milliseconds = elapsed.count();
  std::cout << "[ timing ] " << path.filename().string() << ": " << summary.lasers << " lasers, "
            << summary.odometry << " odometry in " << summary.milliseconds << " ms\n";
  return summary;
}

std::map<std::size_t, std::size_t> only(std::size_t beams, std::size_t scans) { return {{beams, scans}}; }

struct RawLog {
  std::string file;
  std::size_t scans;
  std::size_t beams;
  std::size_t odometry;
  double duration;                 // s, last scan stamp minus first
  std::size_t backwards_lasers;    // steps back in time of the laser stamps
  std::size_t backwards_messages;  // ... of all message stamps in file order
};

TEST(CarmenRealData, RawLogsReadWithTheReadmeCounts) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  // README: Intel's "631 backwards steps" is the laser stream alone; over all messages in file
  // order (ODOM and FLASER interleaved) the stamps step back 889 times. FR079 writes each FLASER
  // after ODOM lines with later stamps, so all-message order steps back at almost every scan.
  const std::vector<RawLog> logs = {{"intel/intel.clf.gz", 13631, 180, 26915, 2691.3, 631, 889},
                                    {"aces/aces.clf.gz", 7374, 180, 7375, 1365.5, 0, 161},
                                    {"fr079/fr079.clf.gz", 4934, 360, 8951, 1061.4, 0, 4932}};
  for (const RawLog& expected : logs) {
    SCOPED_TRACE(expected.file);
    const LogSummary log = summarize(data / expected.file);
    EXPECT_EQ(log.lasers, expected.scans);
    EXPECT_EQ(log.beams, only(expected.beams, expected.scans));
    EXPECT_EQ(log.odometry, expected.odometry);
    EXPECT_NEAR(log.laser_duration(), expected.duration, 0.05);
    EXPECT_EQ(log.stats.backwards_laser_timestamps, expected.backwards_lasers);
    EXPECT_EQ(log.stats.backwards_timestamps, expected.backwards_messages);
    EXPECT_EQ(log.stats.comment_lines, 5u);
    EXPECT_EQ(log.stats.skipped_lines, 0u);
    EXPECT_EQ(log.stats.lines, 5u + expected.scans + expected.odometry);
  }
}

TEST(CarmenRealData, FirstIntelScanHasTheCarmenGeometry) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  CarmenReader reader((data / "intel/intel.clf.gz").string());
  std::optional<SensorMessage> message;
  while ((message = reader.next()) && !std::holds_alternative<LaserMessage>(*message)) {
  }
  ASSERT_TRUE(message);
  const LaserMessage& laser = std::get<LaserMessage>(*message);
  EXPECT_EQ(laser.line, 7u);  // five comments, one ODOM
  EXPECT_EQ(laser.scan.ranges.front(), 1.07);
  EXPECT_NEAR(laser.scan.angle_min, -std::numbers::pi / 2, 1e-15);
  EXPECT_NEAR(laser.scan.angle_increment, std::numbers::pi / 180, 1e-15);
  EXPECT_EQ(laser.scan.stamp, 976052857.337530);
  EXPECT_EQ(laser.scan.range_max, 80.0);  // no PARAM lines: the default
  // Raw logs: the "estimated" triple repeats the odometry triple (0, 0, -0.002458).
  EXPECT_EQ(laser.laser_pose.vector(), laser.odom_pose.vector());
  EXPECT_EQ(laser.odom_pose.theta(), -0.002458);
}

struct CorrectedLog {
  std::string file;
  std::size_t scans;
  std::size_t beams;
  std::size_t odometry;
  double duration;  // s, last scan stamp minus first; negative when the README gives none
};

TEST(CarmenRealData, EveryCorrectedLogReadsWithTheReadmeCounts) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<CorrectedLog> logs = {
      {"intel/intel-corrected.log.gz", 910, 180, 14541, 2650.9},
      {"aces/aces-corrected.log.gz", 440, 180, 7814, 1318.1},
      {"fr079/freiburg-079-corrected.log.gz", 4791, 360, 9725, 1061.3},
      {"carmen-corrected/acapulco-corrected.log.gz", 861, 181, 12142, 1363.9},
      {"carmen-corrected/belgioioso-corrected.log.gz", 395, 361, 4442, -1.0},
      {"carmen-corrected/edmonton-corrected.log.gz", 340, 180, 6351, 708.0},
      {"carmen-corrected/fhw-corrected.log.gz", 488, 180, 13935, 2007.2},
      {"carmen-corrected/freiburg-101-corrected.log.gz", 292, 360, 4569, 918.9},
      {"carmen-corrected/freiburg-campus-corrected.log.gz", 2008, 360, 17691, -1.0},
      {"carmen-corrected/orebro-corrected.log.gz", 237, 181, 255, -1.0},
      {"carmen-corrected/seattle-corrected.log.gz", 241, 361, 19311, 1165.3},
  };
  std::size_t seen = 0;
  for (const CorrectedLog& expected : logs) {
    SCOPED_TRACE(expected.file);
    const LogSummary log = summarize(data / expected.file);
    EXPECT_EQ(log.lasers, expected.scans);
    EXPECT_EQ(log.beams, only(expected.beams, expected.scans));
    EXPECT_EQ(log.odometry, expected.odometry);
    // Every FLASER is followed by a NEFF line, skipped and counted.
    EXPECT_EQ(log.stats.skipped_lines, expected.scans);
    EXPECT_EQ(log.stats.skipped_types, (std::map<std::string, std::size_t>{{"NEFF", expected.scans}}));
    if (expected.duration >= 0.0) {
      EXPECT_NEAR(log.laser_duration(), expected.duration, 0.05);
    }
    ++seen;
  }
  // No corrected log in the data folder is left out of the table above.
  std::size_t on_disk = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(data)) {
    if (entry.path().filename().string().ends_with("-corrected.log.gz")) ++on_disk;
  }
  EXPECT_EQ(on_disk, seen);
}

TEST(CarmenRealData, CorrectedLogParamsSetTheGeometry) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  // Freiburg 101: PARAM robot_front_laser_max 80.99, robot_frontlaser_offset -0.04,
  // laser_front_laser_resolution 0.5 (deg); 360 beams.
  CarmenReader reader((data / "carmen-corrected/freiburg-101-corrected.log.gz").string());
  std::optional<SensorMessage> message;
  while ((message = reader.next()) && !std::holds_alternative<LaserMessage>(*message)) {
  }
  ASSERT_TRUE(message);
  const LaserMessage& laser = std::get<LaserMessage>(*message);
  EXPECT_EQ(laser.scan.range_max, 80.99);
  EXPECT_EQ(laser.scan.T_robot_sensor.x(), -0.04);
  EXPECT_NEAR(laser.scan.angle_increment, std::numbers::pi / 360, 1e-15);
  EXPECT_NEAR(laser.scan.angle_min, -std::numbers::pi / 2, 1e-15);
}

TEST(CarmenRealData, WholeLogWriteReadIsExact) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::string source = (data / "aces/aces.clf.gz").string();
  test::TempDir dir;
  const std::string copy_path = dir.file("aces.clf");  // plain: gzip is covered by the fixture tests
  {
    CarmenReader reader(source);
    CarmenWriter writer(copy_path);
    while (auto message = reader.next()) writer.write(*message);
    writer.commit();
  }
  CarmenReader original(source);
  CarmenReader copy(copy_path);
  std::size_t compared = 0;
  while (auto a = original.next()) {
    auto b = copy.next();
    ASSERT_TRUE(b);
    ASSERT_EQ(a->index(), b->index());
    if (const auto* x = std::get_if<LaserMessage>(&*a)) {
      const auto& y = std::get<LaserMessage>(*b);
      ASSERT_EQ(x->scan.ranges, y.scan.ranges);
      ASSERT_EQ(x->scan.stamp, y.scan.stamp);
      ASSERT_EQ(x->odom_pose.vector(), y.odom_pose.vector());
      ASSERT_EQ(x->laser_pose.vector(), y.laser_pose.vector());
    } else if (const auto* o = std::get_if<OdometryMessage>(&*a)) {
      const auto& p = std::get<OdometryMessage>(*b);
      ASSERT_EQ(o->reading.stamp, p.reading.stamp);
      ASSERT_EQ(o->reading.pose.vector(), p.reading.pose.vector());
      ASSERT_EQ(o->reading.tv, p.reading.tv);
      ASSERT_EQ(o->reading.rv, p.reading.rv);
    }
    ++compared;
  }
  EXPECT_FALSE(copy.next());
  EXPECT_EQ(compared, 7374u + 7375u);
  EXPECT_EQ(copy.stats().backwards_timestamps, original.stats().backwards_timestamps);
}

}  // namespace
}  // namespace slam2d
