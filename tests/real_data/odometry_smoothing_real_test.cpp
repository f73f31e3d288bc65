// SPDX-License-Identifier: BSD-3-Clause
// Hector SLAM's per-scan poses smoothed with the wheel odometry (slam/fusion/odometry_smoothing) on
// FR079, clean and with a noisy laser over its good odometry (perturb's
// laser-noise:sigma=0.1,bearing=1, seed 1): on relations at most 10 s apart the noisy run's poses
// are worse than the odometry alone; smoothed they are better than both, and the clean run stays
// where it was (bench/BENCHMARKS.md, "With the per-scan poses smoothed by the odometry", has the
// figures of `slam2d map --method hector`, the same run).

#include <gtest/gtest.h>

#include <string>
#include <variant>
#include <vector>

#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/sim/fault_injection.hpp"
#include "slam2d/slam/fusion/odometry_smoothing.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "real_data/real_logs.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

double short_relation_error(const std::vector<SE2>& poses, const std::vector<double>& stamps,
                            const std::vector<Relation>& relations) {
  Trajectory trajectory;
  for (std::size_t i = 0; i < poses.size(); ++i) trajectory.push_back(stamps[i], poses[i]);
  return relation_error(trajectory, test::relations_at_most(relations, 10.0)).translation.mean;
}

struct Errors {
  double odometry, method, smoothed;
};

Errors run(std::vector<SensorMessage> messages, const std::vector<Relation>& relations, const std::string& fault) {
  if (!fault.empty()) apply_faults({parse_fault(fault)}, messages, 1);
  HectorSlam slam{HectorSlamConfig{}};
  std::vector<SE2> method, odometry;
  std::vector<double> stamps;
  for (const SensorMessage& message : messages) {
    const auto* laser = std::get_if<LaserMessage>(&message);
    if (laser == nullptr) continue;
    method.push_back(slam.add_scan(laser->scan, HectorInputs{.T_odom_robot = laser->odom_pose}).T_map_robot);
    odometry.push_back(laser->odom_pose);
    stamps.push_back(laser->scan.stamp);
  }
  OdometrySmoothingStats stats;
  const std::vector<SE2> smoothed = smooth_with_odometry(method, odometry, {}, &stats);
  EXPECT_TRUE(stats.applied) << stats.skipped;
  return {short_relation_error(odometry, stamps, relations), short_relation_error(method, stamps, relations),
          short_relation_error(smoothed, stamps, relations)};
}

TEST(OdometrySmoothingRealData, ANoisyLaserOverGoodOdometryDoesNoHarm) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<SensorMessage> messages = test::read_log(data / "fr079/fr079.clf.gz");
  const std::vector<Relation> relations = read_relations((data / "fr079/fr079.relations").string());

  const Errors clean = run(messages, relations, "");
  EXPECT_LT(clean.smoothed, 1.02 * clean.method) << "clean: method " << clean.method;
  EXPECT_LT(clean.smoothed, clean.odometry);

  const Errors noisy = run(messages, relations, "laser-noise:sigma=0.1,bearing=1");
  EXPECT_LT(noisy.smoothed, noisy.odometry) << "noisy laser: method " << noisy.method;
  EXPECT_LT(noisy.smoothed, 0.97 * noisy.method) << "noisy laser: odometry " << noisy.odometry;
}

}  // namespace
}  // namespace slam2d
