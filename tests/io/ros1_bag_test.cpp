// SPDX-License-Identifier: BSD-3-Clause
// ROS 1 bag reader: hand-computed message decodes, the real bags of ../shared/data/bags (counts,
// order, sampled values from checks/*.inspect.json, the lz4/none variants) and corrupted copies.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>

#include "slam2d/io/detail/ros1_messages.hpp"
#include "slam2d/io/ros1_bag.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

// ROS 1 serialization, written by hand.
struct Wire {
  std::vector<std::uint8_t> bytes;
  Wire& u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  Wire& u64(std::uint64_t v) { return u32(static_cast<std::uint32_t>(v)).u32(static_cast<std::uint32_t>(v >> 32)); }
  Wire& f32(float v) { return u32(std::bit_cast<std::uint32_t>(v)); }
  Wire& f64(double v) { return u64(std::bit_cast<std::uint64_t>(v)); }
  Wire& str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
    return *this;
  }
  Wire& header(std::uint32_t sec, std::uint32_t nsec, const std::string& frame) { return u32(7).u32(sec).u32(nsec).str(frame); }
  Wire& zeros(std::size_t n) {
    bytes.insert(bytes.end(), n, 0);
    return *this;
  }
};

TEST(Ros1Decode, LaserScanByHand) {
  Wire wire;
  wire.header(100, 250'000'000, "laser").f32(-1.5f).f32(1.5f).f32(1.0f).f32(0.0f).f32(0.1f).f32(0.2f).f32(30.0f);
  wire.u32(4).f32(1.0f).f32(2.5f).f32(std::numeric_limits<float>::infinity()).f32(std::nanf(""));
  wire.u32(0);
  const DecodedMessage message = ros1::decode_message(ros1::MessageType::kLaserScan, wire.bytes, false);
  const auto& decoded = std::get<DecodedScan>(message);
  EXPECT_EQ(decoded.frame_id, "laser");
  EXPECT_EQ(decoded.scan.stamp, 100.25);
  EXPECT_EQ(decoded.scan.angle_min, -1.5);
  EXPECT_EQ(decoded.scan.angle_increment, 1.0);
  EXPECT_EQ(decoded.scan.range_min, static_cast<double>(0.2f));
  EXPECT_EQ(decoded.scan.range_max, 30.0);
  ASSERT_EQ(decoded.scan.size(), 4u);
  EXPECT_EQ(decoded.scan.ranges[1], 2.5);
  EXPECT_TRUE(std::isinf(decoded.scan.ranges[2]));
  EXPECT_TRUE(std::isnan(decoded.scan.ranges[3]));
  EXPECT_TRUE(decoded.scan.intensities.empty());
  EXPECT_EQ(decoded.scan.T_robot_sensor.translation(), SE2().translation());
}

// A yaw of 90 deg about z: quaternion (0, 0, sin 45, cos 45).
Wire odometry_wire() {
  const double s = std::sqrt(0.5);
  Wire wire;
  wire.header(5, 1, "odom").str("base_link");
  wire.f64(1.5).f64(-2.0).f64(9.0).f64(0.0).f64(0.0).f64(s).f64(s).zeros(36 * 8);
  wire.f64(0.7).f64(0.0).f64(0.0).f64(0.0).f64(0.0).f64(-0.3).zeros(36 * 8);
  return wire;
}

TEST(Ros1Decode, OdometryByHand) {
  const Wire wire = odometry_wire();
  EXPECT_EQ(wire.bytes.size(), 4u + 8 + 8 + 13 + 7 * 8 + 288 + 6 * 8 + 288);
  const auto decoded = std::get<DecodedOdometry>(ros1::decode_message(ros1::MessageType::kOdometry, wire.bytes, false));
  EXPECT_EQ(decoded.frame_id, "odom");
  EXPECT_EQ(decoded.child_frame_id, "base_link");
  EXPECT_EQ(decoded.reading.stamp, 5.0 + 1e-9);
  EXPECT_EQ(decoded.reading.pose.x(), 1.5);
  EXPECT_EQ(decoded.reading.pose.y(), -2.0);
  EXPECT_NEAR(decoded.reading.pose.theta(), std::numbers::pi / 2, 1e-15);
  EXPECT_EQ(decoded.reading.tv, 0.7);
  EXPECT_EQ(decoded.reading.rv, -0.3);
}

TEST(Ros1Decode, TransformsAndImuByHand) {
  Wire tf;
  tf.u32(2);
  tf.header(1, 0, "odom").str("base_link").f64(1).f64(2).f64(3).f64(0).f64(0).f64(1).f64(0);  // yaw pi
  tf.header(2, 0, "base_link").str("laser").f64(0.04).f64(0).f64(0).f64(0).f64(0).f64(0).f64(1);
  const auto transforms = std::get<DecodedTransforms>(ros1::decode_message(ros1::MessageType::kTFMessage, tf.bytes, true));
  EXPECT_TRUE(transforms.is_static);
  ASSERT_EQ(transforms.transforms.size(), 2u);
  EXPECT_EQ(transforms.transforms[0].parent, "odom");
  EXPECT_NEAR(std::abs(transforms.transforms[0].T_parent_child.theta()), std::numbers::pi, 1e-15);
  EXPECT_EQ(transforms.transforms[1].child, "laser");
  EXPECT_EQ(transforms.transforms[1].T_parent_child.x(), 0.04);

  // Roll 0.1 about x: quaternion (sin 0.05, 0, 0, cos 0.05).
  Wire imu;
  imu.header(3, 500'000'000, "imu").f64(std::sin(0.05)).f64(0).f64(0).f64(std::cos(0.05)).zeros(72);
  imu.f64(0).f64(0).f64(0.25).zeros(72).zeros(24 + 72);
  const auto decoded = std::get<DecodedImu>(ros1::decode_message(ros1::MessageType::kImu, imu.bytes, false));
  EXPECT_EQ(decoded.reading.stamp, 3.5);
  EXPECT_NEAR(decoded.reading.roll, 0.1, 1e-12);
  EXPECT_NEAR(decoded.reading.pitch, 0.0, 1e-12);
  EXPECT_EQ(decoded.reading.yaw_rate, 0.25);
}

TEST(Ros1Decode, ShortLongAndOverlongMessagesAreErrors) {
  Wire wire = odometry_wire();
  std::vector<std::uint8_t> bytes = wire.bytes;
  bytes.pop_back();
  EXPECT_THROW(ros1::decode_message(ros1::MessageType::kOdometry, bytes, false), Error);
  bytes = wire.bytes;
  bytes.push_back(0);
  EXPECT_THROW(ros1::decode_message(ros1::MessageType::kOdometry, bytes, false), Error);
  Wire scan;  // a ranges count far past the message
  scan.header(1, 0, "laser").zeros(28).u32(0x40000000).f32(1.0f).u32(0);
  EXPECT_THROW(ros1::decode_message(ros1::MessageType::kLaserScan, scan.bytes, false), Error);
  EXPECT_EQ(ros1::message_type("sensor_msgs/PointCloud2"), std::nullopt);
}

// Every message of `topics`, in the reader's order.
std::vector<DecodedRecord> read_all(BagSource& bag, const std::vector<std::string>& topics) {
  std::vector<DecodedRecord> records;
  while (auto record = bag.next(topics)) records.push_back(std::move(*record));
  return records;
}

const std::vector<std::string> kAllTopics = {"/scan", "/odom", "/tf", "/tf_static"};

// Expected values from ../shared/data/bags/README.md §3 and checks/<name>.inspect.json.
struct RealBag {
  std::string name;
  std::map<std::string, std::size_t> counts;
  std::map<std::string, std::pair<std::string, std::string>> receive_span;  // first and last in file order
  std::size_t beams;
  double angle_increment;  // float32 pi / (beams - 1), as the bags hold it
  double range_max;
  std::size_t at_range_max;
  double min_range, max_range;
  std::string first_scan_stamp;
  std::vector<float> first_ranges;  // scan seq 0, beams 0..4
  double odom_x, odom_y, odom_qz, odom_qw;  // odometry seq 0
  double laser_x;                           // /tf_static base_link -> laser
};

const std::vector<RealBag> kRealBags = {
    {"intel",
     {{"/scan", 13631}, {"/odom", 26915}, {"/tf", 26915}, {"/tf_static", 1}},
     {{"/scan", {"976052857.337530017", "976055548.624744058"}}, {"/odom", {"976052857.337283969", "976055548.625126958"}}},
     180, 0.017550798133015633, 80.0, 68313, 0.20000000298023224, 81.83000183105469, "976052857.337530017",
     {1.07f, 1.07f, 1.08f, 1.08f, 1.08f},
     0.0, 0.0, -0.0012289996906113586, 0.999999244779595, 0.0},
    {"aces",
     {{"/scan", 7374}, {"/odom", 7375}, {"/tf", 7375}, {"/tf_static", 1}},
     {{"/scan", {"70.289900000", "1435.809999000"}}, {"/odom", {"70.179699000", "1435.900000000"}}},
     180, 0.017550798133015633, 50.0, 11139, 0.3100000023841858, 50.0, "70.289900000",
     {46.56f, 47.31f, 12.51f, 14.71f, 12.16f},
     -0.000602, 0.012727, -0.7071066656470943, 0.7071068967259818, 0.0},
    {"fr079",
     {{"/scan", 4934}, {"/odom", 8951}, {"/tf", 8951}, {"/tf_static", 1}},
     {{"/scan", {"1211.520329000", "2272.970282000"}}, {"/odom", {"1211.530144000", "2273.219477000"}}},
     360, 0.008750954642891884, 80.0, 36881, 0.11999999731779099, 81.91000366210938, "1211.520329000",
     {1.67f, 1.65f, 1.64f, 1.63f, 1.63f},
     -3.034287, 8.291214, -0.999946812959906, 0.010313643940275164, 0.04},
};

// "SEC.NSEC" as the reader gives it: sec + nsec * 1e-9.
double seconds(const std::string& text) {
  const std::size_t dot = text.find('.');
  return std::stod(text.substr(0, dot)) + std::stod(text.substr(dot + 1)) * 1e-9;
}

class Ros1RealBag : public ::testing::TestWithParam<RealBag> {};

TEST_P(Ros1RealBag, TopicsCountsOrderAndSampledValues) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const RealBag& expected = GetParam();
  const std::string path = (data / "bags/ros1" / (expected.name + ".orig.bag")).string();
  ASSERT_TRUE(is_ros1_bag(path));
  const auto bag = open_ros1_bag(path);

  std::map<std::string, std::string> types;
  for (const BagTopic& topic : bag->topics()) {
    types[topic.name] = topic.type;
    EXPECT_EQ(topic.count, expected.counts.at(topic.name)) << topic.name;
  }
  EXPECT_EQ(types, (std::map<std::string, std::string>{{"/scan", "sensor_msgs/LaserScan"},
                                                         {"/odom", "nav_msgs/Odometry"},
                                                         {"/tf", "tf2_msgs/TFMessage"},
                                                         {"/tf_static", "tf2_msgs/TFMessage"}}));

  EXPECT_EQ(bag->progress(), 0.0);
  const std::vector<DecodedRecord> records = read_all(*bag, kAllTopics);
  EXPECT_EQ(bag->progress(), 1.0);
  std::map<std::string, std::size_t> counts;
  std::set<std::size_t> indices;
  std::map<std::string, const DecodedRecord*> first_in_file;  // seq 0 of each topic
  std::map<std::string, const DecodedRecord*> last_in_file;
  std::map<std::string, std::pair<double, double>> time_span;  // earliest and latest receive time
  std::size_t at_range_max = 0, nonfinite = 0;
  double min_range = INFINITY, max_range = 0.0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const DecodedRecord& record = records[i];
    ++counts[record.topic];
    indices.insert(record.index);
    if (i > 0) {
      ASSERT_LT(records[i - 1].index, record.index) << i;  // the recording (file) order
    }
    auto& first = first_in_file[record.topic];
    if (!first || record.index < first->index) first = &record;
    auto& last = last_in_file[record.topic];
    if (!last || record.index > last->index) last = &record;
    if (!time_span.contains(record.topic)) time_span[record.topic] = {record.receive_time, record.receive_time};
    time_span[record.topic].first = std::min(time_span[record.topic].first, record.receive_time);
    time_span[record.topic].second = std::max(time_span[record.topic].second, record.receive_time);
    if (const auto* scan = std::get_if<DecodedScan>(&record.message)) {
      ASSERT_EQ(scan->scan.size(), expected.beams);
      EXPECT_EQ(scan->frame_id, "laser");
      EXPECT_EQ(scan->scan.stamp, record.receive_time);  // README §3: receive time = header.stamp
      EXPECT_EQ(scan->scan.angle_min, static_cast<double>(static_cast<float>(-std::numbers::pi / 2)));
      EXPECT_EQ(scan->scan.angle_increment, expected.angle_increment);
      EXPECT_EQ(scan->scan.range_max, expected.range_max);
      for (const double range : scan->scan.ranges) {
        at_range_max += range >= expected.range_max;
        nonfinite += !std::isfinite(range);
        min_range = std::min(min_range, range);
        max_range = std::max(max_range, range);
      }
    } else if (const auto* odometry = std::get_if<DecodedOdometry>(&record.message)) {
      EXPECT_EQ(odometry->reading.stamp, record.receive_time);
      EXPECT_EQ(odometry->child_frame_id, "base_link");
    } else if (const auto* transforms = std::get_if<DecodedTransforms>(&record.message)) {
      EXPECT_EQ(transforms->is_static, record.topic == "/tf_static");
      ASSERT_EQ(transforms->transforms.size(), 1u);
      EXPECT_EQ(transforms->transforms[0].stamp, record.receive_time);
    }
  }
  EXPECT_EQ(counts, expected.counts);
  for (const BagTopic& topic : bag->topics()) {
    EXPECT_EQ(std::pair(topic.first_stamp, topic.last_stamp), time_span.at(topic.name)) << topic.name;
  }
  for (const auto& [topic, span] : expected.receive_span) {
    EXPECT_EQ(first_in_file.at(topic)->receive_time, seconds(span.first)) << topic;
    EXPECT_EQ(last_in_file.at(topic)->receive_time, seconds(span.second)) << topic;
  }
  EXPECT_EQ(indices.size(), records.size());
  EXPECT_EQ(*indices.rbegin(), records.size() - 1);
  EXPECT_EQ(at_range_max, expected.at_range_max);
  EXPECT_EQ(nonfinite, 0u);
  EXPECT_EQ(min_range, expected.min_range);
  EXPECT_EQ(max_range, expected.max_range);

  const auto& first_scan = std::get<DecodedScan>(first_in_file.at("/scan")->message).scan;
  EXPECT_EQ(first_scan.stamp, seconds(expected.first_scan_stamp));
  for (std::size_t beam = 0; beam < expected.first_ranges.size(); ++beam) {
    EXPECT_EQ(first_scan.ranges[beam], static_cast<double>(expected.first_ranges[beam])) << beam;
  }
  const auto& odometry = std::get<DecodedOdometry>(first_in_file.at("/odom")->message);
  EXPECT_EQ(odometry.frame_id, "odom");
  EXPECT_EQ(odometry.reading.pose.x(), expected.odom_x);
  EXPECT_EQ(odometry.reading.pose.y(), expected.odom_y);
  EXPECT_NEAR(odometry.reading.pose.theta(), 2.0 * std::atan2(expected.odom_qz, expected.odom_qw), 1e-12);
  const auto& laser = std::get<DecodedTransforms>(first_in_file.at("/tf_static")->message).transforms.at(0);
  EXPECT_EQ(laser.parent, "base_link");
  EXPECT_EQ(laser.child, "laser");
  EXPECT_EQ(laser.T_parent_child.x(), expected.laser_x);
  EXPECT_EQ(laser.T_parent_child.theta(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Logs, Ros1RealBag, ::testing::ValuesIn(kRealBags),
                         [](const auto& info) { return info.param.name; });

TEST(Ros1Bag, ReadsOnlyTheWantedTopicsAndOdometryBeforeItsTfOnTies) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const auto bag = open_ros1_bag((data / "bags/ros1/fr079.orig.bag").string());
  const std::vector<DecodedRecord> records = read_all(*bag, {"/odom", "/tf", "/missing"});
  ASSERT_EQ(records.size(), 2u * 8951);
  for (std::size_t i = 0; i < records.size(); i += 2) {  // each /odom and its /tf share a stamp
    ASSERT_EQ(records[i].topic, "/odom") << i;
    ASSERT_EQ(records[i + 1].topic, "/tf") << i;
    ASSERT_EQ(records[i].receive_time, records[i + 1].receive_time);
  }
  EXPECT_EQ(bag->next({"/odom"}), std::nullopt);
}

TEST(Ros1Bag, ChangingTheWantedTopicsContinuesAfterTheLastMessage) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const auto bag = open_ros1_bag((data / "bags/ros1/aces_head_lz4.bag").string());
  std::size_t scans = 0;
  std::optional<DecodedRecord> last;
  for (std::size_t i = 0; i < 100; ++i) {
    last = bag->next({"/scan"});
    ASSERT_TRUE(last);
    ++scans;
  }
  while (auto record = bag->next({"/scan", "/odom"})) {
    EXPECT_GE(record->receive_time, last->receive_time);
    scans += record->topic == "/scan";
  }
  EXPECT_EQ(scans, 600u);
}

bool same_double(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

// README §6: the first 600 ACES scans as lz4 and uncompressed chunks, with driver-style +inf/NaN.
TEST(Ros1Bag, Lz4AndUncompressedVariantsDecodeTheSameWithInfAndNaN) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const auto lz4 = open_ros1_bag((data / "bags/ros1/aces_head_lz4.bag").string());
  const auto none = open_ros1_bag((data / "bags/ros1/aces_head_none.bag").string());
  const std::vector<DecodedRecord> a = read_all(*lz4, kAllTopics);
  const std::vector<DecodedRecord> b = read_all(*none, kAllTopics);
  ASSERT_EQ(a.size(), 1801u);
  ASSERT_EQ(b.size(), a.size());
  std::size_t scans = 0, infinite = 0;
  std::vector<std::pair<std::size_t, std::size_t>> nans;  // scan #, beam
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].topic, b[i].topic);
    ASSERT_EQ(a[i].receive_time, b[i].receive_time);
    ASSERT_EQ(a[i].index, b[i].index);
    const auto* scan_a = std::get_if<DecodedScan>(&a[i].message);
    if (!scan_a) continue;
    const auto& scan_b = std::get<DecodedScan>(b[i].message);
    ASSERT_EQ(scan_a->scan.ranges.size(), scan_b.scan.ranges.size());
    for (std::size_t beam = 0; beam < scan_a->scan.size(); ++beam) {
      const double range = scan_a->scan.ranges[beam];
      ASSERT_TRUE(same_double(range, scan_b.scan.ranges[beam]));
      infinite += std::isinf(range) && range > 0;
      if (std::isnan(range)) nans.emplace_back(scans, beam);
    }
    ++scans;
  }
  EXPECT_EQ(scans, 600u);
  EXPECT_EQ(infinite, 910u);
  // The scans are in file order here (no backward step inside /scan).
  EXPECT_EQ(nans, (std::vector<std::pair<std::size_t, std::size_t>>{{7, 0}, {7, 1}, {300, 90}, {300, 91}, {599, 100}, {599, 179}}));
  EXPECT_EQ(a.front().receive_time, 70.179699);
  EXPECT_EQ(a.back().receive_time, 168.06);
}

// Corrupted copies of real bags: an Error naming the file, never a crash.
std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
std::string write_bytes(const test::TempDir& dir, const std::string& name, const std::vector<std::uint8_t>& bytes) {
  const std::string path = dir.file(name);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return path;
}
std::size_t find(const std::vector<std::uint8_t>& bytes, const std::string& needle, std::size_t from = 0) {
  const auto found = std::search(bytes.begin() + static_cast<std::ptrdiff_t>(from), bytes.end(), needle.begin(), needle.end());
  return static_cast<std::size_t>(found - bytes.begin());
}
std::uint32_t get_u32(const std::vector<std::uint8_t>& bytes, std::size_t pos) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | bytes.at(pos + static_cast<std::size_t>(i));
  return v;
}
void put_u32(std::vector<std::uint8_t>& bytes, std::size_t pos, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes.at(pos + static_cast<std::size_t>(i)) = static_cast<std::uint8_t>(v >> (8 * i));
}

// Opening and reading every topic throws an Error whose message starts with the path and holds `needle`.
void expect_bag_error(const std::string& path, const std::string& needle) {
  try {
    const auto bag = open_ros1_bag(path);
    read_all(*bag, kAllTopics);
    ADD_FAILURE() << "no error for " << path;
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

bool same_records(const std::vector<DecodedRecord>& a, const std::vector<DecodedRecord>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].topic != b[i].topic || a[i].receive_time != b[i].receive_time || a[i].message.index() != b[i].message.index()) {
      return false;
    }
  }
  return true;
}

bool has_warning(const BagSource& bag, const std::string& needle) {
  const std::vector<std::string> warnings = bag.warnings();
  return std::any_of(warnings.begin(), warnings.end(), [&](const std::string& w) { return w.find(needle) != std::string::npos; });
}

// A recording that was killed has no index (index_pos 0) and may end inside a chunk: it reads in
// one pass over its chunks, in the same order as the indexed bag, and a tail cut short is left out.
TEST(Ros1Bag, ABagWithoutAnIndexReadsInOnePassAndACutTailIsLeftOut) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const test::TempDir dir;
  for (const char* name : {"aces.orig.bag", "aces_head_lz4.bag", "aces_head_none.bag"}) {
    const std::vector<std::uint8_t> original = read_bytes(data / "bags/ros1" / name);
    const std::vector<DecodedRecord> indexed = read_all(*open_ros1_bag((data / "bags/ros1" / name).string()), kAllTopics);
    std::vector<std::uint8_t> bytes = original;
    std::fill_n(bytes.begin() + static_cast<std::ptrdiff_t>(find(bytes, "index_pos=") + 10), 8, 0);
    const auto unindexed = open_ros1_bag(write_bytes(dir, "unindexed.bag", bytes));
    EXPECT_TRUE(same_records(read_all(*unindexed, kAllTopics), indexed)) << name;
    EXPECT_TRUE(has_warning(*unindexed, "no index")) << name;
    EXPECT_EQ(unindexed->topics().size(), 4u) << name;

    if (std::string(name) != "aces.orig.bag") continue;  // the variants are one chunk each
    bytes.resize(bytes.size() * 2 / 3);  // killed while writing a chunk: the index was never written
    const auto cut = open_ros1_bag(write_bytes(dir, "cut.bag", bytes));
    const std::vector<DecodedRecord> read = read_all(*cut, kAllTopics);
    EXPECT_GT(read.size(), indexed.size() / 3) << "17 chunks, 11 whole";
    ASSERT_LT(read.size(), indexed.size());
    EXPECT_TRUE(same_records(read, {indexed.begin(), indexed.begin() + static_cast<std::ptrdiff_t>(read.size())}));
    EXPECT_TRUE(has_warning(*cut, "cut short"));

    // Killed with a chunk open: rosbag writes its data length when it closes it, so it is 0.
    bytes = original;
    std::fill_n(bytes.begin() + static_cast<std::ptrdiff_t>(find(bytes, "index_pos=") + 10), 8, 0);
    std::size_t record = 13;  // after the magic: walk the records to the third chunk
    for (int chunks = 0;;) {
      const std::size_t header_len = get_u32(bytes, record);
      const std::size_t op = find(bytes, "op=", record + 4);
      if (bytes[op + 3] == 0x05 && ++chunks == 3) break;
      record += 4 + header_len + 4 + get_u32(bytes, record + 4 + header_len);
    }
    const std::size_t data_len = record + 4 + get_u32(bytes, record);
    put_u32(bytes, data_len, 0);
    bytes.resize(data_len + 4);
    const auto open_chunk = open_ros1_bag(write_bytes(dir, "open_chunk.bag", bytes));
    const std::vector<DecodedRecord> before = read_all(*open_chunk, kAllTopics);
    EXPECT_GT(before.size(), 0u);
    EXPECT_TRUE(same_records(before, {indexed.begin(), indexed.begin() + static_cast<std::ptrdiff_t>(before.size())}));
    EXPECT_TRUE(has_warning(*open_chunk, "never closed"));
  }
  // Cut before any message: nothing to read is an error.
  std::vector<std::uint8_t> head = read_bytes(data / "bags/ros1/aces_head_lz4.bag");
  std::fill_n(head.begin() + static_cast<std::ptrdiff_t>(find(head, "index_pos=") + 10), 8, 0);
  head.resize(head.size() / 2);
  expect_bag_error(write_bytes(dir, "nothing.bag", head), "nothing to read");
}

TEST(Ros1Bag, CorruptedBagsAreErrorsNamingTheFile) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const test::TempDir dir;
  const std::vector<std::uint8_t> bz2 = read_bytes(data / "bags/ros1/aces.orig.bag");
  const std::vector<std::uint8_t> none = read_bytes(data / "bags/ros1/aces_head_none.bag");
  const std::vector<std::uint8_t> lz4 = read_bytes(data / "bags/ros1/aces_head_lz4.bag");

  expect_bag_error(write_bytes(dir, "tiny.bag", {bz2.begin(), bz2.begin() + 20}), "bytes at byte");
  expect_bag_error(write_bytes(dir, "empty.bag", {}), "bytes at byte 0");
  expect_bag_error(dir.file("absent.bag"), "cannot open");

  // An unknown compression, in each kind of bag.
  std::vector<std::uint8_t> bytes = bz2;
  std::memcpy(&bytes[find(bytes, "compression=bz2") + 12], "zst", 3);
  expect_bag_error(write_bytes(dir, "zst.bag", bytes), "unknown chunk compression 'zst'");
  bytes = none;
  std::memcpy(&bytes[find(bytes, "compression=none") + 12], "zstd", 4);
  expect_bag_error(write_bytes(dir, "zstd.bag", bytes), "unknown chunk compression 'zstd'");

  // An uncompressed size far beyond the compressed one.
  bytes = bz2;
  put_u32(bytes, find(bytes, "size=", find(bytes, "compression=bz2")) + 5, 0xfffffff0u);
  expect_bag_error(write_bytes(dir, "huge.bag", bytes), "a decompression bomb?");

  // Corrupt compressed data.
  bytes = bz2;
  for (std::size_t i = 20'000; i < 20'100; ++i) bytes[i] ^= 0x5a;
  expect_bag_error(write_bytes(dir, "corrupt_bz2.bag", bytes), "bz2");
  bytes = lz4;
  for (std::size_t i = 20'000; i < 20'100; ++i) bytes[i] ^= 0x5a;
  expect_bag_error(write_bytes(dir, "corrupt_lz4.bag", bytes), "lz4");

  // The first scan in the uncompressed bag: its header's frame_id "laser" then 28 bytes of floats
  // and the ranges count 180.
  std::size_t laser = 0;
  for (laser = find(none, std::string("\x05\0\0\0laser", 9)); laser < none.size();
       laser = find(none, std::string("\x05\0\0\0laser", 9), laser + 1)) {
    if (none[laser + 9 + 28] == 180) break;
  }
  ASSERT_LT(laser, none.size());
  bytes = none;  // a ranges count running past the message
  put_u32(bytes, laser + 9 + 28, 0x1000000u);
  expect_bag_error(write_bytes(dir, "ranges_count.bag", bytes), "/scan message");
  bytes = none;  // the message data record's length (before seq and stamp) running past the chunk
  put_u32(bytes, laser - 12 - 4, 0x7ffffff0u);
  expect_bag_error(write_bytes(dir, "data_len.bag", bytes), "runs past its record");
}

TEST(Ros1Bag, AWantedTopicOfAnotherTypeIsAnErrorNamingIt) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const test::TempDir dir;
  std::vector<std::uint8_t> bytes = read_bytes(data / "bags/ros1/aces_head_none.bag");
  for (std::size_t at = find(bytes, "type=sensor_msgs/LaserScan"); at < bytes.size();
       at = find(bytes, "type=sensor_msgs/LaserScan", at + 1)) {
    std::memcpy(&bytes[at + 17], "PointScan", 9);
  }
  const std::string path = write_bytes(dir, "point_scan.bag", bytes);
  const auto bag = open_ros1_bag(path);
  EXPECT_EQ(read_all(*bag, {"/odom"}).size(), 600u);
  try {
    bag->next({"/scan"});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
    EXPECT_NE(what.find("/scan has type sensor_msgs/PointScan"), std::string::npos) << what;
  }
}

TEST(Ros1Bag, IsRos1BagChecksTheMagic) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const test::TempDir dir;
  EXPECT_TRUE(is_ros1_bag((data / "bags/ros1/aces_head_lz4.bag").string()));
  EXPECT_FALSE(is_ros1_bag(write_bytes(dir, "text.bag", {'#', 'R', 'O', 'S'})));
  EXPECT_FALSE(is_ros1_bag(dir.file("absent.bag")));
  EXPECT_FALSE(is_ros1_bag((data / "bags/ros2/aces_head_mcap_lz4/aces_head_mcap_lz4_0.mcap").string()));
}

}  // namespace
}  // namespace slam2d
