// SPDX-License-Identifier: BSD-3-Clause
// The ROS 2 readers (MCAP, rosbag2 sqlite3) on the real bags of shared/data/bags/ros2 (README §3,
// §4, §6): counts, order, the same decoded messages from every storage of one log, the driver-style
// ranges of the variants, and corrupted copies that must be errors naming the file.

#include <gtest/gtest.h>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "slam2d/io/mcap.hpp"
#include "slam2d/io/rosbag2.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kAllTopics = {"/scan", "/odom", "/tf", "/tf_static"};

std::string hex(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

/// Every decoded field of a record (floats exactly), to compare records of two files.
std::string describe(const DecodedRecord& record) {
  std::string out = record.topic + " " + hex(record.receive_time);
  if (const auto* scan = std::get_if<DecodedScan>(&record.message)) {
    out += " scan " + scan->frame_id + " " + hex(scan->scan.stamp) + " " + hex(scan->scan.angle_min) + " " +
           hex(scan->scan.angle_increment) + " " + hex(scan->scan.range_min) + " " + hex(scan->scan.range_max);
    for (double r : scan->scan.ranges) out += " " + hex(r);
    out += " i" + std::to_string(scan->scan.intensities.size());
  } else if (const auto* odom = std::get_if<DecodedOdometry>(&record.message)) {
    const OdometryReading& r = odom->reading;
    out += " odom " + odom->frame_id + " " + odom->child_frame_id + " " + hex(r.stamp) + " " + hex(r.pose.x()) + " " +
           hex(r.pose.y()) + " " + hex(r.pose.theta()) + " " + hex(r.tv) + " " + hex(r.rv);
  } else if (const auto* tf = std::get_if<DecodedTransforms>(&record.message)) {
    out += tf->is_static ? " tf_static" : " tf";
    for (const DecodedTransform& t : tf->transforms) {
      out += " " + t.parent + ">" + t.child + " " + hex(t.stamp) + " " + hex(t.T_parent_child.x()) + " " +
             hex(t.T_parent_child.y()) + " " + hex(t.T_parent_child.theta());
    }
  }
  return out;
}

std::vector<DecodedRecord> read_all(BagSource& source, const std::vector<std::string>& wanted = kAllTopics) {
  std::vector<DecodedRecord> records;
  while (auto record = source.next(wanted)) records.push_back(std::move(*record));
  EXPECT_EQ(source.progress(), 1.0);
  return records;
}

std::map<std::string, std::size_t> counts(const BagSource& source) {
  std::map<std::string, std::size_t> out;
  for (const BagTopic& topic : source.topics()) out[topic.name] = topic.count;
  return out;
}

void expect_log(const fs::path& folder, const std::map<std::string, std::size_t>& expected, std::size_t beams) {
  SCOPED_TRACE(folder.string());
  const auto source = open_rosbag2(folder.string());
  EXPECT_EQ(counts(*source), expected);
  const std::vector<DecodedRecord> records = read_all(*source);
  std::map<std::string, std::size_t> seen;
  double last = -1.0;
  for (const DecodedRecord& record : records) {
    ++seen[record.topic];
    EXPECT_GE(record.receive_time, last);
    last = record.receive_time;
    if (const auto* scan = std::get_if<DecodedScan>(&record.message)) {
      EXPECT_EQ(scan->scan.size(), beams);
      EXPECT_EQ(scan->frame_id, "laser");
      EXPECT_EQ(scan->scan.stamp, record.receive_time);  // README §3: receive time = header.stamp
    }
  }
  EXPECT_EQ(seen, expected);
}

const std::map<std::string, std::size_t> kAces = {{"/scan", 7374}, {"/odom", 7375}, {"/tf", 7375}, {"/tf_static", 1}};
const std::map<std::string, std::size_t> kFr079 = {{"/scan", 4934}, {"/odom", 8951}, {"/tf", 8951}, {"/tf_static", 1}};

TEST(Ros2BagsReal, CountsOrderAndBeamsOfEveryStorage) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const fs::path ros2 = data / "bags" / "ros2";
  test::TempDir tmp;
  expect_log(ros2 / "aces_mcap", kAces, 180);
  expect_log(ros2 / "fr079_mcap", kFr079, 360);
  expect_log(test::unpack_rosbag2(ros2 / "aces_db3", tmp.path()), kAces, 180);
  expect_log(test::unpack_rosbag2(ros2 / "fr079_db3", tmp.path()), kFr079, 360);
}

TEST(Ros2BagsReal, ZstdUncompressedAndSqliteGiveTheSameMessages) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const fs::path ros2 = data / "bags" / "ros2";
  test::TempDir tmp;
  const auto zstd = read_all(*open_rosbag2((ros2 / "aces_mcap").string()));
  const auto plain = read_all(*open_rosbag2(test::unpack_rosbag2(ros2 / "aces_mcap_uncompressed", tmp.path()).string()));
  const auto db3 = read_all(*open_rosbag2(test::unpack_rosbag2(ros2 / "aces_db3", tmp.path()).string()));
  ASSERT_EQ(zstd.size(), 22125u);
  ASSERT_EQ(plain.size(), zstd.size());
  ASSERT_EQ(db3.size(), zstd.size());
  for (std::size_t i = 0; i < zstd.size(); ++i) {
    const std::string expected = describe(zstd[i]);
    ASSERT_EQ(describe(plain[i]), expected) << "record " << i;
    ASSERT_EQ(describe(db3[i]), expected) << "record " << i;
  }
}

TEST(Ros2BagsReal, Fr079StaticTransformAndOnlyTheWantedTopics) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const auto source = open_rosbag2((data / "bags" / "ros2" / "fr079_mcap").string());
  const auto records = read_all(*source, {"/tf_static", "/scan"});
  ASSERT_EQ(records.size(), 4935u);
  const auto& tf = std::get<DecodedTransforms>(records.front().message);
  EXPECT_TRUE(tf.is_static);
  ASSERT_EQ(tf.transforms.size(), 1u);
  EXPECT_EQ(tf.transforms[0].parent, "base_link");
  EXPECT_EQ(tf.transforms[0].child, "laser");
  EXPECT_EQ(tf.transforms[0].T_parent_child.x(), 0.04);
  EXPECT_EQ(tf.transforms[0].T_parent_child.y(), 0.0);
  EXPECT_EQ(tf.transforms[0].T_parent_child.theta(), 0.0);
}

TEST(Ros2BagsReal, Lz4AndNoSummaryVariantsGiveTheSame600ScansWithInfAndNan) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const fs::path ros2 = data / "bags" / "ros2";
  const auto lz4 = read_all(*open_rosbag2((ros2 / "aces_head_mcap_lz4").string()));
  const auto streamed = read_all(*open_rosbag2((ros2 / "aces_head_mcap_nosummary").string()));
  ASSERT_EQ(lz4.size(), 1801u);
  ASSERT_EQ(streamed.size(), lz4.size());
  std::size_t scans = 0, infinite = 0, nan = 0;
  for (std::size_t i = 0; i < lz4.size(); ++i) {
    ASSERT_EQ(describe(streamed[i]), describe(lz4[i])) << "record " << i;
    if (const auto* scan = std::get_if<DecodedScan>(&lz4[i].message)) {
      for (std::size_t beam = 0; beam < scan->scan.size(); ++beam) {
        const double r = scan->scan.ranges[beam];
        infinite += std::isinf(r) && r > 0;
        if (std::isnan(r)) {
          ++nan;
          EXPECT_TRUE(scans == 7 || scans == 300 || scans == 599) << "scan " << scans << " beam " << beam;
        }
      }
      ++scans;
    }
  }
  EXPECT_EQ(scans, 600u);
  EXPECT_EQ(infinite, 910u);
  EXPECT_EQ(nan, 6u);
  EXPECT_EQ(lz4.back().receive_time, 168.06);
}

// --- corrupted copies -------------------------------------------------------------------------

std::vector<char> slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

void spit(const fs::path& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// File offset of the first top-level record with `opcode` (walking from the header).
std::size_t first_record(const std::vector<char>& bytes, unsigned char opcode) {
  for (std::size_t offset = 8; offset + 9 <= bytes.size();) {
    std::uint64_t length;
    std::memcpy(&length, bytes.data() + offset + 1, 8);
    if (static_cast<unsigned char>(bytes[offset]) == opcode) return offset;
    offset += 9 + length;
  }
  ADD_FAILURE() << "no record with opcode " << int(opcode);
  return 0;
}

/// `bytes` with the DataEnd record's data section CRC zeroed ("not checked"), so that a change
/// inside the data section reaches the check that names it more precisely.
std::vector<char> without_data_crc(std::vector<char> bytes) {
  std::memset(bytes.data() + first_record(bytes, 0x0F) + 9, 0, 4);
  return bytes;
}

/// Reading the whole file fails with an Error whose message starts with the path and has `needle`.
void expect_bad(const fs::path& file, const std::string& needle) {
  try {
    auto source = open_mcap(file.string());
    read_all(*source);
    ADD_FAILURE() << "no error for " << file << " (" << needle << ")";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(file.string() + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

TEST(Ros2BagsReal, CorruptedMcapCopiesAreErrorsNamingTheFile) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  test::TempDir tmp;
  const std::vector<char> lz4 = slurp(data / "bags/ros2/aces_head_mcap_lz4/aces_head_mcap_lz4_0.mcap");
  const std::vector<char> streamed = slurp(data / "bags/ros2/aces_head_mcap_nosummary/aces_head_mcap_nosummary_0.mcap");
  const std::size_t chunk = first_record(lz4, 0x06);
  const std::string at_chunk = "chunk at offset " + std::to_string(chunk) + ": ";

  std::vector<char> bytes(lz4.begin(), lz4.begin() + static_cast<std::ptrdiff_t>(lz4.size() / 2));
  spit(tmp.path() / "truncated.mcap", bytes);
  expect_bad(tmp.path() / "truncated.mcap", "runs past the end of the file");

  bytes.assign(streamed.begin(), streamed.begin() + static_cast<std::ptrdiff_t>(streamed.size() / 2));
  spit(tmp.path() / "truncated_stream.mcap", bytes);
  expect_bad(tmp.path() / "truncated_stream.mcap", "runs past the end of the file");

  bytes = without_data_crc(lz4);  // the chunk's compression string "lz4" (3 bytes) after 3 u64 and the CRC
  const std::size_t compression = chunk + 9 + 24 + 4;
  ASSERT_EQ(std::string(bytes.data() + compression + 4, 3), "lz4");
  std::memcpy(bytes.data() + compression, "\x02\x00\x00\x00xz", 6);  // "xz", the next byte now in the records' length
  spit(tmp.path() / "xz.mcap", bytes);
  expect_bad(tmp.path() / "xz.mcap", at_chunk + "unknown compression 'xz'");

  bytes = without_data_crc(lz4);
  bytes[chunk + 9 + 24] ^= 0x5a;
  spit(tmp.path() / "crc.mcap", bytes);
  expect_bad(tmp.path() / "crc.mcap", at_chunk + "CRC mismatch");

  for (const std::vector<char>* file : {&lz4, &streamed}) {  // a byte of the header's library name, in no chunk
    bytes = *file;
    bytes[8 + 9 + 4 + 4 + 4] ^= 0x20;
    spit(tmp.path() / "data_crc.mcap", bytes);
    expect_bad(tmp.path() / "data_crc.mcap", "data section CRC mismatch");
  }

  bytes = without_data_crc(lz4);
  const std::uint64_t huge_size = std::uint64_t{1} << 40;
  std::memcpy(bytes.data() + chunk + 9 + 16, &huge_size, 8);
  spit(tmp.path() / "size.mcap", bytes);
  expect_bad(tmp.path() / "size.mcap", "a decompression bomb?");

  bytes = without_data_crc(lz4);
  const std::uint64_t past_end = lz4.size();
  std::memcpy(bytes.data() + chunk + 1, &past_end, 8);
  spit(tmp.path() / "length.mcap", bytes);
  expect_bad(tmp.path() / "length.mcap", "runs past the end of the file");

  bytes = streamed;  // a message record longer than what is left of the file
  std::memcpy(bytes.data() + first_record(streamed, 0x05) + 1, &past_end, 8);
  spit(tmp.path() / "message.mcap", bytes);
  expect_bad(tmp.path() / "message.mcap", "runs past the end of the file");

  bytes = without_data_crc(streamed);  // a scan's ranges count larger than its message
  const std::size_t message = first_record(streamed, 0x05);
  std::size_t scan = message;
  for (std::uint64_t length = 0; scan < streamed.size(); scan += 9 + length) {
    std::memcpy(&length, bytes.data() + scan + 1, 8);
    if (bytes[scan] == 0x05 && length == 22 + 780) break;  // a 180-beam LaserScan
  }
  ASSERT_LT(scan, streamed.size());
  const std::uint32_t beams = 100000;
  std::memcpy(bytes.data() + scan + 9 + 22 + 4 + 48, &beams, 4);
  spit(tmp.path() / "ranges.mcap", bytes);
  expect_bad(tmp.path() / "ranges.mcap", "on /scan: truncated CDR message: a sequence of 100000 ranges");

  bytes = without_data_crc(lz4);
  bytes[1] = 'X';
  spit(tmp.path() / "magic.mcap", bytes);
  expect_bad(tmp.path() / "magic.mcap", "not an MCAP file");
}

TEST(Ros2BagsReal, BadRosbag2FoldersAreErrorsNamingTheMetadata) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  test::TempDir tmp;
  const fs::path folder = test::unpack_rosbag2(data / "bags/ros2/aces_head_mcap_lz4", tmp.path());
  const fs::path metadata = folder / "metadata.yaml";
  std::ifstream in(metadata);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  auto expect_error = [&](const std::string& changed, const std::string& needle) {
    std::ofstream(metadata) << changed;
    try {
      open_rosbag2(folder.string());
      ADD_FAILURE() << "no error (" << needle << ")";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(metadata.string() + ":", 0), 0u) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  };
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string out = text;
    const std::size_t at = out.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? out : out.replace(at, from.size(), to);
  };
  expect_error(replaced("storage_identifier: mcap", "storage_identifier: hdf5"), "unknown storage_identifier 'hdf5'");
  expect_error(replaced("- aces_head_mcap_lz4_0.mcap", "- missing_0.mcap"), "does not exist");
  EXPECT_TRUE(is_rosbag2(folder.string()));
  EXPECT_TRUE(is_rosbag2(metadata.string()));
  EXPECT_FALSE(is_rosbag2(tmp.path().string()));
  EXPECT_TRUE(is_mcap((folder / "aces_head_mcap_lz4_0.mcap").string()));
  EXPECT_FALSE(is_mcap(metadata.string()));
  EXPECT_THROW(open_rosbag2(tmp.file("nothing")), Error);
  EXPECT_THROW(open_rosbag2_sqlite(metadata.string()), Error);  // not a database
}

}  // namespace
}  // namespace slam2d
