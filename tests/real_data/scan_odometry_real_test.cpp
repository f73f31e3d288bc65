// SPDX-License-Identifier: BSD-3-Clause
// Scan-to-scan odometry with PL-ICP (Censi 2008) on the raw logs of Kuemmerle et al. 2009, with
// the defaults of `slam2d odometry --matcher pl-icp`: the relation error must beat the log's own
// wheel odometry and CSM's sm2 (default parameters, the same wheel odometry as guess: Intel
// 0.911 m, ACES 0.629 m, FR079 0.531 m) on every log. One run of a log is one draw of its heading
// drift (most of the error is on relations minutes long), so the median over 1 cm range-noise
// seeds is bounded too. The bounds sit a little above what was measured (docs/methods/pl_icp.md
// has the table); one default configuration for every log.

#include <gtest/gtest.h>

#include <iostream>
#include <string>
#include <variant>
#include <vector>

#include <algorithm>
#include <cstdint>

#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "slam2d/registration/scan_odometry.hpp"
#include "slam2d/sim/fault_injection.hpp"
#include "real_data/real_logs.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

struct OdometryLog {
  const char* name;
  const char* log;
  const char* relations;
  double max_trans_mean;         // m
  double max_rot_mean_deg;       // deg
  double max_median_over_seeds;  // m, the median over three 1 cm range-noise seeds
};

// PL-ICP scan odometry over the log's front-laser scans, with each scan's wheel odometry as guess.
Trajectory pl_icp_odometry(const std::vector<SensorMessage>& messages, Trajectory* wheel = nullptr,
                           std::size_t* failures = nullptr) {
  ScanOdometry odometry([](const PointCloud2& target, const PointCloud2& source, const SE2& guess) {
    return match_pl_icp(target, source, guess);
  });
  for (const SensorMessage& message : messages) {
    const auto* laser = std::get_if<LaserMessage>(&message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    odometry.add(laser->scan, laser->odom_pose);
    if (wheel) wheel->push_back(laser->scan.stamp, laser->odom_pose);
  }
  if (failures) *failures = odometry.stats().failures;
  return odometry.trajectory();
}

void PrintTo(const OdometryLog& log, std::ostream* os) { *os << log.name; }

class ScanOdometryRealData : public ::testing::TestWithParam<OdometryLog> {};

TEST_P(ScanOdometryRealData, PlIcpBeatsWheelOdometryOnRelations) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const OdometryLog& log = GetParam();
  const std::vector<Relation> relations = read_relations((data / log.relations).string());
  Trajectory wheel;
  std::size_t failures = 0;
  const Trajectory trajectory = pl_icp_odometry(test::read_log(data / log.log), &wheel, &failures);
  const RelationErrorResult matched = relation_error(trajectory, relations);
  const RelationErrorResult raw = relation_error(wheel, relations);
  std::cout << "[ measured ] " << log.name << ": pl-icp " << matched.translation.mean << " m / "
            << matched.rotation_deg.mean << " deg, odometry " << raw.translation.mean << " m / "
            << raw.rotation_deg.mean << " deg, " << failures << " failures of " << trajectory.size() << " scans\n";
  EXPECT_EQ(matched.missing, 0u);
  EXPECT_EQ(trajectory.size(), wheel.size());
  EXPECT_LT(matched.translation.mean, raw.translation.mean) << log.name;
  EXPECT_LT(matched.translation.mean, log.max_trans_mean) << log.name;
  EXPECT_LT(matched.rotation_deg.mean, log.max_rot_mean_deg) << log.name;
  EXPECT_LT(failures, trajectory.size() / 100) << log.name;
}

TEST_P(ScanOdometryRealData, MedianOverRangeNoiseSeedsStaysBounded) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const OdometryLog& log = GetParam();
  const std::vector<Relation> relations = read_relations((data / log.relations).string());
  const std::vector<SensorMessage> clean = test::read_log(data / log.log);
  std::vector<double> errors;
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    std::vector<SensorMessage> messages = clean;
    apply_faults({parse_fault("range-noise:sigma=0.01")}, messages, seed);
    errors.push_back(relation_error(pl_icp_odometry(messages), relations).translation.mean);
  }
  std::sort(errors.begin(), errors.end());
  std::cout << "[ measured ] " << log.name << ": pl-icp over seeds " << errors[0] << " " << errors[1] << " "
            << errors[2] << " m\n";
  EXPECT_LT(errors[1], log.max_median_over_seeds) << log.name;
}

// Measured with the local map of two keyframes (mean translational / rotational relation error,
// wheel odometry in brackets; then the three seeds): Intel 0.668 m / 3.5 deg (7.37 m; 0.439 0.393
// 0.405 m), ACES 0.430 m / 1.3 deg (0.549 m; 0.312 0.327 0.307 m), FR079 0.516 m / 4.4 deg (5.03 m;
// 0.417 0.522 0.710 m). With the keyframe alone (local_map_keyframes 1): Intel 0.946 m (seeds 0.753
// 0.548 0.543), ACES 0.389 m / 0.7 deg (0.416 0.372 0.364), FR079 0.465 m (0.662 1.307 1.793).
// Each clean bound is CSM's sm2 (Intel 0.911, ACES 0.629, FR079 0.531 m) or 10-15 % above the
// measurement, whichever is lower; the seed medians' sit 10-15 % above theirs.
INSTANTIATE_TEST_SUITE_P(
    Kuemmerle2009, ScanOdometryRealData,
    ::testing::Values(OdometryLog{"intel", "intel/intel.clf.gz", "intel/intel.relations", 0.76, 3.9, 0.46},
                      OdometryLog{"aces", "aces/aces.clf.gz", "aces/aces.relations", 0.49, 1.45, 0.35},
                      OdometryLog{"fr079", "fr079/fr079.clf.gz", "fr079/fr079.relations", 0.531, 5.0, 0.60}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace slam2d
