// SPDX-License-Identifier: BSD-3-Clause
// The bag assembly (io/bag_log.hpp) over a hand-made BagSource: topic choice, the laser's mounting
// from the static transforms, the odometry interpolated at each scan, /tf as the odometry, time
// order, and "no return" readings passed through as published.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/io/bag_log.hpp"

namespace slam2d {
namespace {

// A bag whose messages are given in time order.
class FakeSource : public BagSource {
 public:
  FakeSource(std::vector<BagTopic> topics, std::vector<DecodedRecord> records)
      : topics_(std::move(topics)), records_(std::move(records)) {}
  const std::string& path() const override { return path_; }
  const std::vector<BagTopic>& topics() const override { return topics_; }
  std::optional<DecodedRecord> next(const std::vector<std::string>& wanted) override {
    while (at_ < records_.size()) {
      const DecodedRecord& record = records_[at_++];
      if (std::find(wanted.begin(), wanted.end(), record.topic) != wanted.end()) return record;
    }
    return std::nullopt;
  }
  double progress() const override { return records_.empty() ? 1.0 : static_cast<double>(at_) / records_.size(); }

 private:
  std::string path_ = "fake.bag";
  std::vector<BagTopic> topics_;
  std::vector<DecodedRecord> records_;
  std::size_t at_ = 0;
};

DecodedRecord scan(double stamp, std::vector<double> ranges = {1.0, 2.0, 3.0}, const std::string& topic = "/scan") {
  DecodedScan decoded;
  decoded.frame_id = "laser";
  decoded.scan.stamp = stamp;
  decoded.scan.angle_min = -0.1;
  decoded.scan.angle_increment = 0.1;
  decoded.scan.range_min = 0.1;
  decoded.scan.range_max = 30.0;
  decoded.scan.ranges = std::move(ranges);
  return {topic, stamp, 0, decoded};
}

DecodedRecord odometry(double stamp, const SE2& pose) {
  DecodedOdometry decoded{.frame_id = "odom", .child_frame_id = "base_link", .reading = {.stamp = stamp, .pose = pose}};
  return {"/odom", stamp, 0, decoded};
}

DecodedRecord static_transform(const std::string& parent, const std::string& child, const SE2& T) {
  return {"/tf_static", 0.0, 0, DecodedTransforms{.is_static = true, .transforms = {{0.0, parent, child, T}}}};
}

const std::vector<BagTopic> kTopics = {{"/scan", "sensor_msgs/msg/LaserScan", 0, 0.0, 0.0},
                                       {"/odom", "nav_msgs/Odometry", 0, 0.0, 0.0},
                                       {"/tf_static", "tf2_msgs/TFMessage", 0, 0.0, 0.0}};

std::vector<SensorMessage> read_all(BagLogReader& reader) {
  std::vector<SensorMessage> messages;
  while (auto message = reader.next()) messages.push_back(std::move(*message));
  return messages;
}

TEST(BagLog, EachScanGetsTheOdometryInterpolatedAtItsStampInTimeOrder) {
  BagLogReader reader(std::make_unique<FakeSource>(
      kTopics, std::vector<DecodedRecord>{static_transform("base_link", "laser", SE2(0.04, 0.0, 0.0)),
                                          odometry(0.0, SE2(0.0, 0.0, 0.0)), scan(0.5), odometry(1.0, SE2(1.0, 0.0, 0.2)),
                                          scan(1.5)}));
  const std::vector<SensorMessage> messages = read_all(reader);
  ASSERT_EQ(messages.size(), 4u);
  ASSERT_TRUE(std::holds_alternative<OdometryMessage>(messages[0]));
  const auto& first = std::get<LaserMessage>(messages[1]);
  EXPECT_TRUE(first.has_poses);
  EXPECT_NEAR(first.odom_pose.x(), 0.5, 1e-12);
  EXPECT_NEAR(first.odom_pose.theta(), 0.1, 1e-12);
  EXPECT_NEAR(first.scan.T_robot_sensor.x(), 0.04, 1e-12) << "the mounting from /tf_static";
  ASSERT_TRUE(std::holds_alternative<OdometryMessage>(messages[2]));
  const auto& last = std::get<LaserMessage>(messages[3]);  // after the last reading: held
  EXPECT_NEAR(last.odom_pose.x(), 1.0, 1e-12);
  EXPECT_EQ(reader.choice().scan_topic, "/scan");
  EXPECT_EQ(reader.choice().odom_topic, "/odom");
  EXPECT_EQ(reader.choice().base_frame, "base_link");
  EXPECT_TRUE(reader.warnings().empty());
}

// A recorded log whose stamps step back (Intel: scans up to 0.9 s out of order): the scans keep
// the bag's order and each gets the odometry at its own stamp, from the readings around it.
TEST(BagLog, StampsThatStepBackKeepTheBagsOrderAndTheirOwnOdometry) {
  BagLogReader reader(std::make_unique<FakeSource>(
      kTopics, std::vector<DecodedRecord>{odometry(0.0, SE2()), odometry(2.0, SE2(2.0, 0.0, 0.0)), scan(1.5),
                                          odometry(1.0, SE2(1.0, 0.0, 0.0)), scan(0.5), odometry(3.0, SE2(3.0, 0.0, 0.0)),
                                          scan(2.5)}));
  std::vector<double> stamps, xs;
  for (const SensorMessage& message : read_all(reader)) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) {
      stamps.push_back(laser->scan.stamp);
      xs.push_back(laser->odom_pose.x());
    }
  }
  EXPECT_EQ(stamps, (std::vector<double>{1.5, 0.5, 2.5}));
  ASSERT_EQ(xs.size(), 3u);
  EXPECT_NEAR(xs[0], 1.5, 1e-12);  // between the readings at 1 and 2 s (1 s arrived after it)
  EXPECT_NEAR(xs[1], 0.5, 1e-12);
  EXPECT_NEAR(xs[2], 2.5, 1e-12);
}

// A reading whose stamp is wrong (recorded before the reading at 1 s, stamped 1.4 s): a scan at
// 1.5 s recorded between the readings at 1 and 2 s is interpolated between those two, not between
// the reading stamped 1.4 s and the one at 2 s (the Intel log's clock steps back).
std::vector<DecodedRecord> a_reading_with_a_wrong_stamp() {
  return {odometry(0.0, SE2()), odometry(1.4, SE2(0.5, 0.0, 0.0)), odometry(1.0, SE2(1.0, 0.0, 0.0)), scan(1.5),
          odometry(2.0, SE2(2.0, 0.0, 0.0))};
}

double odometry_x_of_the_scan(BagLogReader& reader) {
  for (const SensorMessage& message : read_all(reader)) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) return laser->odom_pose.x();
  }
  return std::nan("");
}

TEST(BagLog, TheReadingsRecordedAroundAScanBeatAStampFromElsewhere) {
  BagLogReader interpolated(std::make_unique<FakeSource>(kTopics, a_reading_with_a_wrong_stamp()));
  EXPECT_NEAR(odometry_x_of_the_scan(interpolated), 1.5, 1e-12);
  BagLogReader latest(std::make_unique<FakeSource>(kTopics, a_reading_with_a_wrong_stamp()),
                      BagSelection{.scan_odometry = OdometryAtScan::kLatest});
  EXPECT_NEAR(odometry_x_of_the_scan(latest), 1.0, 1e-12) << "the reading recorded just before the scan";
}

// A scan recorded after a reading stamped later than it (topics interleave): interpolated at its
// stamp between the readings around it in time.
TEST(BagLog, AScanRecordedLateIsInterpolatedAtItsStamp) {
  BagLogReader reader(std::make_unique<FakeSource>(
      kTopics, std::vector<DecodedRecord>{odometry(0.0, SE2()), odometry(1.0, SE2(1.0, 0.0, 0.0)),
                                          odometry(2.0, SE2(2.0, 0.0, 0.0)), scan(0.25), odometry(3.0, SE2(3.0, 0.0, 0.0))}));
  EXPECT_NEAR(odometry_x_of_the_scan(reader), 0.25, 1e-12);
}

TEST(BagLog, GeometryOverridesReplaceWhatTheScanDeclares) {
  ScanGeometryOverrides fov;
  fov.field_of_view = 0.6;  // 3 beams, odd: 2 steps of 0.3, from -0.3
  BagLogReader reader(std::make_unique<FakeSource>(kTopics, std::vector<DecodedRecord>{odometry(0.0, SE2()), scan(0.0)}),
                      BagSelection{}, fov);
  const std::vector<SensorMessage> messages = read_all(reader);  // kept: the scan is read from it
  const LaserScan& laser = std::get<LaserMessage>(messages.back()).scan;
  EXPECT_NEAR(laser.angle_min, -0.3, 1e-15);
  EXPECT_NEAR(laser.angle_increment, 0.3, 1e-15);
  EXPECT_EQ(laser.range_max, 30.0) << "not overridden: as declared";

  ScanGeometryOverrides bad;
  bad.angle_increment = -0.1;
  EXPECT_THROW(BagLogReader(std::make_unique<FakeSource>(kTopics, std::vector<DecodedRecord>{}), BagSelection{}, bad), Error);
}

// 180 beams over exactly 180 deg, as a converter writes CARMEN's 1 deg beams: a warning naming
// --fov, not given when the geometry is overridden or the count is odd (181 beams span 180 deg).
TEST(BagLog, AConvertersHalfTurnOverAnEvenBeamCountIsWarnedOf) {
  const auto warnings_for = [](std::size_t beams, ScanGeometryOverrides overrides) {
    DecodedRecord record = scan(0.0, std::vector<double>(beams, 1.0));
    auto& decoded = std::get<DecodedScan>(record.message);
    decoded.scan.angle_min = static_cast<float>(-std::numbers::pi / 2);
    decoded.scan.angle_increment = static_cast<float>(std::numbers::pi / static_cast<double>(beams - 1));
    BagLogReader reader(std::make_unique<FakeSource>(kTopics, std::vector<DecodedRecord>{odometry(0.0, SE2()), record,
                                                                                         static_transform("base_link", "laser", SE2())}),
                        BagSelection{}, overrides);
    read_all(reader);
    return reader.warnings();
  };
  const std::vector<std::string> warned = warnings_for(180, {});
  ASSERT_EQ(warned.size(), 1u);
  EXPECT_NE(warned[0].find("--fov 180"), std::string::npos) << warned[0];
  EXPECT_TRUE(warnings_for(181, {}).empty());
  ScanGeometryOverrides fov;
  fov.field_of_view = std::numbers::pi;
  EXPECT_TRUE(warnings_for(360, fov).empty());
  EXPECT_EQ(warnings_for(360, {}).size(), 1u);
}

// The Intel bag's case: 180 beams declared over exactly 180 deg; CARMEN's 180 beams of 1 deg are
// -90 .. +89 deg, which --fov 180 gives back.
TEST(ScanGeometry, AFieldOfViewOverEvenBeamsIsCarmensSpacing) {
  LaserScan scan;
  scan.ranges.assign(180, 1.0);
  scan.angle_min = -std::numbers::pi / 2;
  scan.angle_increment = std::numbers::pi / 179;
  scan.range_max = 80.0;
  ScanGeometryOverrides overrides;
  overrides.field_of_view = std::numbers::pi;
  overrides.range_max = 50.0;
  apply_overrides(scan, overrides);
  EXPECT_DOUBLE_EQ(scan.angle_increment, std::numbers::pi / 180);
  EXPECT_DOUBLE_EQ(scan.angle_min, -std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(scan.angle_max(), std::numbers::pi / 2 - std::numbers::pi / 180);
  EXPECT_EQ(scan.range_max, 50.0);
  ScanGeometryOverrides first_beam;
  first_beam.angle_min = -1.0;
  apply_overrides(scan, first_beam);
  EXPECT_EQ(scan.angle_min, -1.0);
  EXPECT_DOUBLE_EQ(scan.angle_increment, std::numbers::pi / 180) << "kept";
  EXPECT_EQ(beam_steps(181), 180u);
  EXPECT_EQ(beam_steps(180), 180u);
  EXPECT_EQ(beam_steps(1), 1u);
}

TEST(BagLog, ImuReadingsPassThrough) {
  std::vector<BagTopic> topics = kTopics;
  topics.push_back({"/imu", "sensor_msgs/msg/Imu", 0, 0.0, 0.0});
  BagLogReader reader(std::make_unique<FakeSource>(
      topics, std::vector<DecodedRecord>{odometry(0.0, SE2()),
                                         {"/imu", 0.5, 0, DecodedImu{"imu_link", {0.5, 0.01, -0.02, 0.3}}}}));
  const std::vector<SensorMessage> messages = read_all(reader);
  ASSERT_EQ(messages.size(), 2u);
  const ImuReading& imu = std::get<ImuMessage>(messages[1]).reading;
  EXPECT_EQ(imu.stamp, 0.5);
  EXPECT_EQ(imu.roll, 0.01);
  EXPECT_EQ(imu.pitch, -0.02);
  EXPECT_EQ(imu.yaw_rate, 0.3);
  EXPECT_EQ(stamp_of(messages[1]), 0.5);
  EXPECT_EQ(reader.choice().imu_topic, "/imu");
}

TEST(BagLog, AStaticTransformTheOtherWayRoundIsInverted) {
  BagLogReader reader(std::make_unique<FakeSource>(
      kTopics, std::vector<DecodedRecord>{static_transform("laser", "base_link", SE2(-0.1, 0.0, 0.0)),
                                          odometry(0.0, SE2()), scan(0.0)}));
  const std::vector<SensorMessage> messages = read_all(reader);
  EXPECT_NEAR(std::get<LaserMessage>(messages.back()).scan.T_robot_sensor.x(), 0.1, 1e-12);
}

TEST(BagLog, NoReturnReadingsPassThroughAsPublished) {
  const double inf = std::numeric_limits<double>::infinity();
  BagLogReader reader(std::make_unique<FakeSource>(
      kTopics, std::vector<DecodedRecord>{odometry(0.0, SE2()), scan(0.0, {1.0, inf, std::nan(""), 45.0, 0.01})}));
  const std::vector<SensorMessage> messages = read_all(reader);
  const LaserScan& laser = std::get<LaserMessage>(messages.back()).scan;
  ASSERT_EQ(laser.size(), 5u);
  EXPECT_TRUE(laser.is_valid(0));
  for (std::size_t beam = 1; beam < 5; ++beam) EXPECT_FALSE(laser.is_valid(beam)) << beam;  // inf, NaN, > max, < min
  EXPECT_NEAR(std::get<LaserMessage>(messages.back()).field_of_view, 0.4, 1e-12);
}

TEST(BagLog, WithoutAnOdometryTopicTheOdometryIsOdomToBaseOnTf) {
  const std::vector<BagTopic> topics = {{"/scan", "sensor_msgs/LaserScan", 0, 0.0, 0.0},
                                        {"/tf", "tf2_msgs/msg/TFMessage", 0, 0.0, 0.0}};
  const auto tf = [](double stamp, const SE2& pose) {
    return DecodedRecord{"/tf", stamp, 0,
                         DecodedTransforms{.transforms = {{stamp, "odom", "base_link", pose}, {stamp, "map", "odom", SE2()}}}};
  };
  BagLogReader reader(std::make_unique<FakeSource>(
      topics, std::vector<DecodedRecord>{tf(0.0, SE2()), scan(0.25), tf(1.0, SE2(2.0, 0.0, 0.0))}));
  const std::vector<SensorMessage> messages = read_all(reader);
  ASSERT_EQ(messages.size(), 3u);
  EXPECT_NEAR(std::get<LaserMessage>(messages[1]).odom_pose.x(), 0.5, 1e-12);
  EXPECT_EQ(reader.choice().odom_topic, "/tf");
}

TEST(BagLog, WithoutOdometryTheScansSayTheyHaveNoPoses) {
  BagLogReader reader(std::make_unique<FakeSource>(std::vector<BagTopic>{{"/scan", "sensor_msgs/LaserScan", 0, 0.0, 0.0}},
                                                   std::vector<DecodedRecord>{scan(0.0), scan(0.1)}));
  const std::vector<SensorMessage> messages = read_all(reader);
  ASSERT_EQ(messages.size(), 2u);
  EXPECT_FALSE(std::get<LaserMessage>(messages[0]).has_poses);
  ASSERT_EQ(reader.warnings().size(), 2u);  // and no mounting: no /tf_static
  EXPECT_NE(reader.warnings()[0].find("no odometry"), std::string::npos);
  EXPECT_NE(reader.warnings()[1].find("base_link -> laser"), std::string::npos);
}

TEST(BagLog, TheTopicChoiceIsAutomaticOnlyWhenUnambiguous) {
  const std::vector<BagTopic> two = {{"/front", "sensor_msgs/LaserScan", 0, 0.0, 0.0},
                                     {"/rear", "sensor_msgs/msg/LaserScan", 0, 0.0, 0.0},
                                     {"/odom", "nav_msgs/Odometry", 0, 0.0, 0.0}};
  try {
    choose_topics("two.bag", two, {});
    FAIL() << "two scan topics chosen silently";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("/front"), std::string::npos) << message;
    EXPECT_NE(message.find("/rear"), std::string::npos) << message;
    EXPECT_NE(message.find("--scan-topic"), std::string::npos) << message;
  }
  EXPECT_EQ(choose_topics("two.bag", two, {.scan_topic = "/rear"}).scan_topic, "/rear");
  EXPECT_THROW(choose_topics("two.bag", two, {.scan_topic = "/odom"}), Error);   // not a LaserScan
  EXPECT_THROW(choose_topics("two.bag", two, {.scan_topic = "/side"}), Error);   // no such topic
  EXPECT_THROW(choose_topics("none.bag", {{"/odom", "nav_msgs/Odometry", 0, 0.0, 0.0}}, {}), Error);
  EXPECT_EQ(ros_type_name("sensor_msgs/msg/LaserScan"), "sensor_msgs/LaserScan");
  EXPECT_EQ(ros_type_name("nav_msgs/Odometry"), "nav_msgs/Odometry");
}

}  // namespace
}  // namespace slam2d
