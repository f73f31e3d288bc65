// The real logs as bags (../shared/data/bags, written by third-party tools): `slam2d info` on a
// bag, and `slam2d map` on a bag against the same log's CARMEN file: the same scans and, on ACES,
// a relation error within 10% of the CARMEN run's (the bags spread the beams over exactly 180 deg
// and carry the odometry on its own topic, so the inputs differ slightly).

#include <gtest/gtest.h>

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
      run_command(slam2d("map --quiet --json --method " + method + " --out " + out.path().string() + " " + log));
  EXPECT_EQ(map.exit_code, 0) << map.errors;
  const CommandResult eval =
      run_command(slam2d("eval --json " + out.file("trajectory.txt") + " --relations " + relations));
  EXPECT_EQ(eval.exit_code, 0) << eval.errors;
  return {json_number(map.output, "scans").value_or(-1.0), json_number(eval.output, "trans_mean").value_or(1e9)};
}

// ACES: graph SLAM on the ROS 1 bag within 10% of the CARMEN run, and the MCAP conversion of the
// same bag gives the identical trajectory. (Intel and FR079 are not yet within 10%: the Intel
// bag's scan stamps go backwards, so its time order is not the recording order; FR079's
// /tf_static mounts the laser 4 cm ahead of base_link, and the relations are of the laser's pose.)
TEST(BagMapping, GraphSlamOnAcesMatchesTheCarmenRunAndTheFormatsAgree) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::string relations = (data / "aces/aces.relations").string();
  const auto [carmen_scans, carmen_error] = map_and_eval((data / "aces/aces.clf.gz").string(), "graph", relations);
  test::TempDir ros1_out;
  test::TempDir mcap_out;
  for (const auto& [bag, out] : {std::pair{data / "bags/ros1/aces.orig.bag", &ros1_out},
                                 std::pair{data / "bags/ros2/aces_mcap", &mcap_out}}) {
    const CommandResult map = run_command(
        slam2d("map --quiet --json --method graph --out " + out->path().string() + " " + bag.string()));
    ASSERT_EQ(map.exit_code, 0) << map.errors;
    EXPECT_EQ(json_number(map.output, "scans"), carmen_scans);
    const CommandResult eval =
        run_command(slam2d("eval --json " + out->file("trajectory.txt") + " --relations " + relations));
    const double error = json_number(eval.output, "trans_mean").value_or(1e9);
    EXPECT_LT(error, 1.1 * carmen_error) << bag << ": " << error << " m, CARMEN " << carmen_error << " m";
  }
  EXPECT_EQ(read_text(ros1_out.file("trajectory.txt")), read_text(mcap_out.file("trajectory.txt")))
      << "the ROS 1 bag and its MCAP conversion give the same trajectory";
  EXPECT_EQ(carmen_scans, 7374.0);
}

}  // namespace
}  // namespace slam2d
