// SPDX-License-Identifier: BSD-3-Clause
// The CDR decoder on hand-made buffers: one LaserScan written byte by byte, in both byte orders,
// and cut short at every length.

#include "slam2d/io/detail/cdr.hpp"
#include "slam2d/io/detail/ros_quaternion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace slam2d {
namespace {

/// Writes XCDR1 fields as rmw does: aligned to their size from the end of the 4-byte header.
class CdrWriter {
 public:
  explicit CdrWriter(bool little_endian) : little_(little_endian) {
    bytes_ = {0, static_cast<std::uint8_t>(little_endian ? 1 : 0), 0, 0};
  }
  template <typename T>
  void put(T value) {
    while ((bytes_.size() - 4) % sizeof(T) != 0) bytes_.push_back(0);
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    if (!little_) std::reverse(raw, raw + sizeof(T));  // the tests run on little-endian machines
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
  }
  void string(const std::string& text) {
    put<std::uint32_t>(static_cast<std::uint32_t>(text.size() + 1));
    bytes_.insert(bytes_.end(), text.begin(), text.end());
    bytes_.push_back(0);
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  bool little_;
  std::vector<std::uint8_t> bytes_;
};

std::vector<std::uint8_t> laser_scan(bool little_endian, const std::vector<float>& ranges) {
  CdrWriter out(little_endian);
  out.put<std::int32_t>(12);          // stamp.sec
  out.put<std::uint32_t>(500000000);  // stamp.nanosec
  out.string("laser");
  out.put<float>(-1.5f);   // angle_min
  out.put<float>(1.5f);    // angle_max
  out.put<float>(0.75f);   // angle_increment
  out.put<float>(0.0f);    // time_increment
  out.put<float>(0.1f);    // scan_time
  out.put<float>(0.25f);   // range_min
  out.put<float>(30.0f);   // range_max
  out.put<std::uint32_t>(static_cast<std::uint32_t>(ranges.size()));
  for (float r : ranges) out.put<float>(r);
  out.put<std::uint32_t>(1);  // intensities
  out.put<float>(7.0f);
  return out.bytes();
}

TEST(Cdr, DecodesAHandMadeLaserScanInBothByteOrders) {
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> ranges = {1.0f, 2.5f, inf, std::nanf(""), 4.0f};
  for (const bool little : {true, false}) {
    const std::vector<std::uint8_t> bytes = laser_scan(little, ranges);
    // header 8 + "laser" 4 + 6, pad 2, 7 floats, count + 5 ranges, count + 1 intensity
    EXPECT_EQ(bytes.size(), 4u + 8 + 10 + 2 + 28 + 4 + 20 + 4 + 4);
    const DecodedMessage message = detail::decode_cdr(detail::Ros2Type::kLaserScan, bytes.data(), bytes.size(), false);
    const auto& decoded = std::get<DecodedScan>(message);
    EXPECT_EQ(decoded.frame_id, "laser");
    EXPECT_DOUBLE_EQ(decoded.scan.stamp, 12.5);
    EXPECT_EQ(decoded.scan.angle_min, -1.5);
    EXPECT_EQ(decoded.scan.angle_increment, 0.75);
    EXPECT_EQ(decoded.scan.range_min, 0.25);
    EXPECT_EQ(decoded.scan.range_max, 30.0);
    ASSERT_EQ(decoded.scan.ranges.size(), 5u);
    EXPECT_EQ(decoded.scan.ranges[1], 2.5);
    EXPECT_TRUE(std::isinf(decoded.scan.ranges[2]));
    EXPECT_TRUE(std::isnan(decoded.scan.ranges[3]));
    EXPECT_EQ(decoded.scan.ranges[4], 4.0);
    ASSERT_EQ(decoded.scan.intensities.size(), 1u);
    EXPECT_EQ(decoded.scan.intensities[0], 7.0);
    EXPECT_EQ(decoded.scan.angle_max(), 1.5);
  }
}

TEST(Cdr, EveryTruncationIsAnErrorNotAnOutOfBoundsRead) {
  const std::vector<std::uint8_t> bytes = laser_scan(true, {1.0f, 2.0f, 3.0f});
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    const std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size));
    EXPECT_THROW(detail::decode_cdr(detail::Ros2Type::kLaserScan, cut.data(), cut.size(), false), detail::CdrError)
        << size;
  }
}

TEST(Cdr, AHugeSequenceCountIsRefusedBeforeAllocating) {
  std::vector<std::uint8_t> bytes = laser_scan(true, {1.0f});
  const std::size_t count_at = 4 + 8 + 10 + 2 + 28;
  const std::uint32_t huge = 0xfffffff0u;
  std::memcpy(bytes.data() + count_at, &huge, sizeof huge);
  try {
    detail::decode_cdr(detail::Ros2Type::kLaserScan, bytes.data(), bytes.size(), false);
    ADD_FAILURE() << "no error";
  } catch (const detail::CdrError& e) {
    EXPECT_NE(std::string(e.what()).find("ranges"), std::string::npos) << e.what();
  }
}

TEST(Cdr, RefusesAnotherEncapsulation) {
  std::vector<std::uint8_t> bytes = laser_scan(true, {1.0f});
  bytes[1] = 3;  // PL_CDR_LE
  EXPECT_THROW(detail::decode_cdr(detail::Ros2Type::kLaserScan, bytes.data(), bytes.size(), false), detail::CdrError);
}

TEST(Cdr, DecodesATransformAndTheYawOfItsQuaternion) {
  CdrWriter out(true);
  out.put<std::uint32_t>(1);
  out.put<std::int32_t>(3);
  out.put<std::uint32_t>(0);
  out.string("base_link");
  out.string("laser");
  for (double v : {0.04, -0.5, 0.0}) out.put<double>(v);
  const double yaw = 0.3;
  for (double v : {0.0, 0.0, std::sin(yaw / 2), std::cos(yaw / 2)}) out.put<double>(v);
  const DecodedMessage message =
      detail::decode_cdr(detail::Ros2Type::kTFMessage, out.bytes().data(), out.bytes().size(), true);
  const auto& tf = std::get<DecodedTransforms>(message);
  EXPECT_TRUE(tf.is_static);
  ASSERT_EQ(tf.transforms.size(), 1u);
  EXPECT_EQ(tf.transforms[0].parent, "base_link");
  EXPECT_EQ(tf.transforms[0].child, "laser");
  EXPECT_EQ(tf.transforms[0].stamp, 3.0);
  EXPECT_EQ(tf.transforms[0].T_parent_child.x(), 0.04);
  EXPECT_EQ(tf.transforms[0].T_parent_child.y(), -0.5);
  EXPECT_NEAR(tf.transforms[0].T_parent_child.theta(), yaw, 1e-12);
  EXPECT_NEAR(detail::quaternion_yaw(0, 0, 1, 0), std::numbers::pi, 1e-12);
}

TEST(Cdr, KnowsTheFourTypes) {
  EXPECT_EQ(detail::ros2_type("sensor_msgs/msg/LaserScan"), detail::Ros2Type::kLaserScan);
  EXPECT_EQ(detail::ros2_type("sensor_msgs/msg/Imu"), detail::Ros2Type::kImu);
  EXPECT_FALSE(detail::ros2_type("sensor_msgs/LaserScan"));
  EXPECT_THROW(detail::wanted_type("b.mcap", "/points", "sensor_msgs/msg/PointCloud2", "cdr"), Error);
  EXPECT_THROW(detail::wanted_type("b.mcap", "/scan", "sensor_msgs/msg/LaserScan", "json"), Error);
}

}  // namespace
}  // namespace slam2d
