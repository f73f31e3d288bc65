// SPDX-License-Identifier: BSD-3-Clause
// Bags on the command line, on a simulated run: `convert` between every format and back (the same
// trajectory from each), and `--mcap` of `map` and `localize` read back by slam2d's MCAP reader
// (the poses on /tf are the trajectory written, one scan per pose).

#include <gtest/gtest.h>

#include <filesystem>
#include <map>

#include "slam2d/io/mcap.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::json_number;
using test::run_command;

using test::slam2d;

// 30 s of the simulated office, shared by the tests of this file.
const test::SimulatedLog& run() {
  static const test::SimulatedLog simulated(30, 7);
  return simulated;
}

Trajectory map_trajectory(const std::string& log, const TempDir& out, const std::string& name) {
  const CommandResult mapped =
      run_command(slam2d("map --quiet --method graph --out " + out.file(name) + " " + log));
  EXPECT_EQ(mapped.exit_code, 0) << mapped.errors;
  return read_trajectory(out.file(name + "/trajectory.txt"));
}

void expect_same(const Trajectory& a, const Trajectory& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].stamp, b[i].stamp) << what << " " << i;
    ASSERT_EQ(a[i].pose.vector(), b[i].pose.vector()) << what << " " << i;
  }
}

TEST(BagCli, ConvertToEveryBagFormatAndBackMapsTheSame) {
  TempDir out;
  std::map<std::string, Trajectory> trajectories;
  for (const std::string name : {"sim.mcap", "sim_rosbag2", "sim.bag"}) {
    const CommandResult converted = run_command(slam2d("convert --json " + run().log() + " " + out.file(name)));
    ASSERT_EQ(converted.exit_code, 0) << name << ": " << converted.errors;
    EXPECT_NEAR(*json_number(converted.output, "scans"), 300, 2) << name;
    trajectories[name] = map_trajectory(out.file(name), out, name + "_map");
    const CommandResult info = run_command(slam2d("info --json " + out.file(name)));
    ASSERT_EQ(info.exit_code, 0) << info.errors;
    EXPECT_NE(info.output.find("\"/scan\""), std::string::npos) << info.output;
  }
  expect_same(trajectories["sim.mcap"], trajectories["sim_rosbag2"], "mcap vs rosbag2");
  expect_same(trajectories["sim.mcap"], trajectories["sim.bag"], "mcap vs ros1");
  // A bag back to CARMEN keeps each scan's odometry pose and geometry: the same run.
  ASSERT_EQ(run_command(slam2d("convert --quiet " + out.file("sim.mcap") + " " + out.file("back.clf"))).exit_code, 0);
  expect_same(trajectories["sim.mcap"], map_trajectory(out.file("back.clf"), out, "back_map"), "mcap vs mcap -> carmen");
  // The bag's run is close to the CARMEN log's (the bag interpolates the odometry readings at each scan).
  const Trajectory carmen = map_trajectory(run().log(), out, "carmen_map");
  ASSERT_EQ(carmen.size(), trajectories["sim.mcap"].size());
  for (std::size_t i = 0; i < carmen.size(); ++i) {
    EXPECT_LT((carmen[i].pose.translation() - trajectories["sim.mcap"][i].pose.translation()).norm(), 0.1) << i;
  }
}

TEST(BagCli, ConvertRefusesWhatItCannotDo) {
  TempDir out;
  const CommandResult missing = run_command(slam2d("convert " + out.file("none.bag") + " " + out.file("x.mcap")));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.errors.find("none.bag"), std::string::npos) << missing.errors;
  const CommandResult format = run_command(slam2d("convert --to zip " + run().log() + " " + out.file("x")));
  EXPECT_NE(format.exit_code, 0);
  std::filesystem::create_directories(out.path() / "notabag");
  const CommandResult folder = run_command(slam2d("convert " + run().log() + " " + out.file("notabag")));
  EXPECT_NE(folder.exit_code, 0);
  EXPECT_NE(folder.errors.find("not a rosbag2 folder"), std::string::npos) << folder.errors;
  EXPECT_FALSE(std::filesystem::exists(out.path() / "x.mcap"));
}

// The poses on /tf (map -> base_link), one per /scan, are the trajectory written.
void expect_run_mcap(const std::string& path, const Trajectory& trajectory) {
  ASSERT_TRUE(is_mcap(path)) << path;
  std::unique_ptr<BagSource> source = open_mcap(path);
  std::map<std::string, std::string> types;
  std::map<std::string, std::size_t> counts;
  for (const BagTopic& topic : source->topics()) {
    types[topic.name] = topic.type;
    counts[topic.name] = topic.count;
  }
  EXPECT_EQ(types["/map"], "nav_msgs/msg/OccupancyGrid");
  EXPECT_EQ(types["/path"], "nav_msgs/msg/Path");
  EXPECT_EQ(types["/pose"], "geometry_msgs/msg/PoseStamped");
  EXPECT_EQ(types["/scan_map"], "sensor_msgs/msg/PointCloud2");
  EXPECT_EQ(counts["/map"], 1u);
  EXPECT_EQ(counts["/scan"], trajectory.size());
  EXPECT_EQ(counts["/scan_map"], trajectory.size());
  std::size_t poses = 0;
  std::size_t scans = 0;
  while (auto record = source->next({"/tf", "/scan"})) {
    if (const auto* tf = std::get_if<DecodedTransforms>(&record->message)) {
      ASSERT_LT(poses, trajectory.size());
      ASSERT_EQ(tf->transforms.size(), 1u);
      EXPECT_EQ(tf->transforms[0].parent, "map");
      EXPECT_NEAR(tf->transforms[0].stamp, trajectory[poses].stamp, 1e-6);
      EXPECT_NEAR((tf->transforms[0].T_parent_child.translation() - trajectory[poses].pose.translation()).norm(), 0.0, 1e-9);
      ++poses;
    } else {
      ++scans;
    }
  }
  EXPECT_EQ(poses, trajectory.size());
  EXPECT_EQ(scans, trajectory.size());
}

TEST(BagCli, MapAndLocalizeWriteTheirRunForFoxglove) {
  TempDir out;
  const CommandResult mapped = run_command(slam2d("map --quiet --method graph --out " + out.file("map") + " --mcap " +
                                                  out.file("map.mcap") + " " + run().log()));
  ASSERT_EQ(mapped.exit_code, 0) << mapped.errors;
  expect_run_mcap(out.file("map.mcap"), read_trajectory(out.file("map/trajectory.txt")));

  const CommandResult localized = run_command(slam2d("localize --quiet --method mcl --global --particles 500 --seed 1 --map " + out.file("map/map.yaml") +
                                                     " --out " + out.file("ekf.txt") + " --mcap " + out.file("ekf.mcap") +
                                                     " " + run().log()));
  ASSERT_EQ(localized.exit_code, 0) << localized.errors;
  expect_run_mcap(out.file("ekf.mcap"), read_trajectory(out.file("ekf.txt")));
}

}  // namespace
}  // namespace slam2d
