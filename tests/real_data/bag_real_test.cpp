// SPDX-License-Identifier: BSD-3-Clause
// The real logs as bags (../shared/data/bags, written by third-party tools): `slam2d info` on a
// bag, and `slam2d map` on a bag against the same log's CARMEN file: the same scans and a relation
// error close to the CARMEN run's (the bags spread the beams over exactly 180 deg and carry the
// odometry on its own topic, so the inputs differ).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>

#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::json_number;
using test::run_command;

std::string slam2d(const std::string& arguments) { return test::cli_command(arguments); }

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(BagCli, InfoListsTheTopicsAndWhatItUses) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const CommandResult result = run_command(slam2d("info --json --quiet " + (data / "bags/ros1/fr079.orig.bag").string()));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  EXPECT_NE(result.output.find("\"format\": \"ros1\""), std::string::npos) << result.output;
  EXPECT_EQ(json_number(result.output, "scans"), 4934.0);
  EXPECT_EQ(json_number(result.output, "beams"), 360.0);
  EXPECT_EQ(json_number(result.output, "odom_messages"), 8951.0);
  EXPECT_NEAR(*json_number(result.output, "fov_deg"), 180.0, 1e-4);
  EXPECT_NEAR(*json_number(result.output, "laser_x"), 0.04, 1e-9) << "base_link -> laser from /tf_static";
  EXPECT_NE(result.output.find("\"scan_topic\": \"/scan\""), std::string::npos);
  EXPECT_NE(result.output.find("\"odom_topic\": \"/odom\""), std::string::npos);
  EXPECT_EQ(json_number(result.output, "scans_without_odometry"), 0.0);
}

// `slam2d map LOG --method METHOD` then `eval`: the scan count and the mean translational error.
std::pair<double, double> map_and_eval(const std::string& log, const std::string& method, const std::string& relations) {
  test::TempDir out;
  const CommandResult map =
      run_command(slam2d("map --quiet --json --trajectory-frame sensor --method " + method + " --out " +
                         out.path().string() + " " + log));
  EXPECT_EQ(map.exit_code, 0) << map.errors;
  const CommandResult eval =
      run_command(slam2d("eval --json " + out.file("trajectory.txt") + " --relations " + relations));
  EXPECT_EQ(eval.exit_code, 0) << eval.errors;
  return {json_number(map.output, "scans").value_or(-1.0), json_number(eval.output, "trans_mean").value_or(1e9)};
}

// Bad bags on the command line: a missing topic and a truncated file name the bag, exit 1, write nothing.
TEST(BagCli, AMissingTopicOrATruncatedBagIsAnErrorNamingItWithoutOutput) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  test::TempDir dir;
  const std::string bag = (data / "bags/ros1/aces_head_lz4.bag").string();
  const CommandResult missing =
      run_command(slam2d("map --quiet --method graph --scan-topic /nope --out " + dir.file("a") + " " + bag));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.errors.find(bag + ": no topic /nope"), std::string::npos) << missing.errors;
  EXPECT_NE(missing.errors.find("/scan"), std::string::npos) << "names the candidates: " << missing.errors;
  const std::string text = read_text(bag);
  const std::string truncated = dir.file("truncated.bag");
  std::ofstream(truncated, std::ios::binary) << text.substr(0, text.size() / 2);
  const CommandResult cut = run_command(slam2d("map --quiet --method graph --out " + dir.file("b") + " " + truncated));
  EXPECT_EQ(cut.exit_code, 1);
  EXPECT_EQ(cut.errors.rfind(truncated + ": ", 0), 0u) << cut.errors;
  EXPECT_FALSE(std::filesystem::exists(dir.file("a")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("b")));
}

struct BagLog {
  const char* name;
  const char* bag;
  const char* carmen;
  const char* relations;
  double scans;
  double allowed_ratio;  // bag error / CARMEN error
};

void PrintTo(const BagLog& log, std::ostream* os) { *os << log.name; }

class BagMapping : public ::testing::TestWithParam<BagLog> {};

// Graph SLAM on the ROS 1 bag against the CARMEN run, both as the laser's trajectory (the frame of
// the benchmark's relations; FR079's /tf_static mounts the laser 4 cm ahead of base_link): within
// 10% on ACES and FR079. Intel's bag spreads its 180 beams over 180 deg where the log's sensor
// covers 179 deg (1 deg steps): the CARMEN log read with the bag's angles already scores 0.027 m
// against 0.018 m, so Intel is held to 1.9x until the bag's geometry can be corrected.
TEST_P(BagMapping, GraphSlamOnTheBagMatchesTheCarmenRun) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const BagLog& log = GetParam();
  const std::string relations = (data / log.relations).string();
  const auto [carmen_scans, carmen_error] = map_and_eval((data / log.carmen).string(), "graph", relations);
  const auto [bag_scans, bag_error] = map_and_eval((data / log.bag).string(), "graph", relations);
  EXPECT_EQ(carmen_scans, log.scans);
  EXPECT_EQ(bag_scans, log.scans);
  EXPECT_LT(bag_error, log.allowed_ratio * carmen_error) << "bag " << bag_error << " m, CARMEN " << carmen_error << " m";
}

INSTANTIATE_TEST_SUITE_P(Kuemmerle2009, BagMapping,
                         ::testing::Values(BagLog{"intel", "bags/ros1/intel.orig.bag", "intel/intel.clf.gz",
                                                  "intel/intel.relations", 13631, 1.9},
                                           BagLog{"aces", "bags/ros1/aces.orig.bag", "aces/aces.clf.gz",
                                                  "aces/aces.relations", 7374, 1.1},
                                           BagLog{"fr079", "bags/ros1/fr079.orig.bag", "fr079/fr079.clf.gz",
                                                  "fr079/fr079.relations", 4934, 1.1}),
                         [](const auto& info) { return std::string(info.param.name); });

// The ROS 1 bag and its MCAP conversion give the identical trajectory.
TEST(BagMapping, TheRos1BagAndItsMcapConversionGiveTheSameTrajectory) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  test::TempDir ros1_out;
  test::TempDir mcap_out;
  for (const auto& [bag, out] : {std::pair{data / "bags/ros1/aces.orig.bag", &ros1_out},
                                 std::pair{data / "bags/ros2/aces_mcap", &mcap_out}}) {
    const CommandResult map =
        run_command(slam2d("map --quiet --method graph --out " + out->path().string() + " " + bag.string()));
    ASSERT_EQ(map.exit_code, 0) << map.errors;
  }
  EXPECT_EQ(read_text(ros1_out.file("trajectory.txt")), read_text(mcap_out.file("trajectory.txt")));
}

}  // namespace
}  // namespace slam2d
