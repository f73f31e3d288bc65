// SPDX-License-Identifier: BSD-3-Clause
// Scan-to-scan odometry with PL-ICP (Censi 2008) on the raw logs of Kuemmerle et al. 2009, with
// the defaults of `slam2d odometry --matcher pl-icp`: the relation error must beat the log's own
// wheel odometry on every log and, on Intel, CSM's sm2 with default parameters (0.824 m). The
// bounds sit a little above what was measured (docs/methods/pl_icp.md has the table); one default
// configuration for every log.

#include <gtest/gtest.h>

#include <iostream>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "slam2d/registration/scan_odometry.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

struct OdometryLog {
  const char* name;
  const char* log;
  const char* relations;
  double max_trans_mean;    // m
  double max_rot_mean_deg;  // deg
};

void PrintTo(const OdometryLog& log, std::ostream* os) { *os << log.name; }

class ScanOdometryRealData : public ::testing::TestWithParam<OdometryLog> {};

TEST_P(ScanOdometryRealData, PlIcpBeatsWheelOdometryOnRelations) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const OdometryLog& log = GetParam();
  const std::vector<Relation> relations = read_relations((data / log.relations).string());
  ScanOdometry odometry([](const PointCloud2& target, const PointCloud2& source, const SE2& guess) {
    return match_pl_icp(target, source, guess);
  });
  Trajectory wheel;
  CarmenReader reader((data / log.log).string());
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    odometry.add(laser->scan, laser->odom_pose);
    wheel.push_back(laser->scan.stamp, laser->odom_pose);
  }
  const RelationErrorResult matched = relation_error(odometry.trajectory(), relations);
  const RelationErrorResult raw = relation_error(wheel, relations);
  std::cout << "[ measured ] " << log.name << ": pl-icp " << matched.translation.mean << " m / "
            << matched.rotation_deg.mean << " deg, odometry " << raw.translation.mean << " m / "
            << raw.rotation_deg.mean << " deg, " << odometry.stats().failures << " failures of "
            << odometry.stats().scans << " scans\n";
  EXPECT_EQ(matched.missing, 0u);
  EXPECT_EQ(odometry.trajectory().size(), wheel.size());
  EXPECT_LT(matched.translation.mean, raw.translation.mean) << log.name;
  EXPECT_LT(matched.translation.mean, log.max_trans_mean) << log.name;
  EXPECT_LT(matched.rotation_deg.mean, log.max_rot_mean_deg) << log.name;
  EXPECT_LT(odometry.stats().failures, odometry.stats().scans / 100) << log.name;
}

// Measured (mean translational / rotational relation error, wheel odometry in brackets): Intel
// 0.791 m / 3.7 deg (7.37 m), ACES 0.415 m / 1.1 deg (0.549 m), FR079 1.74 m / 10.7 deg (5.03 m).
// Intel's bound is CSM's figure; the others sit 10-20 % above the measurement. FR079 with its
// odometry as logged (reversing integrated as forward, 6.50 m) scored 1.83 m / 8.1 deg: the
// reader's repair of the reversing improves the translation, and moves the heading drift of the
// longest relations, which no loop closure bounds.
INSTANTIATE_TEST_SUITE_P(
    Kuemmerle2009, ScanOdometryRealData,
    ::testing::Values(OdometryLog{"intel", "intel/intel.clf.gz", "intel/intel.relations", 0.824, 4.5},
                      OdometryLog{"aces", "aces/aces.clf.gz", "aces/aces.relations", 0.5, 1.4},
                      OdometryLog{"fr079", "fr079/fr079.clf.gz", "fr079/fr079.relations", 2.2, 12.5}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace slam2d
