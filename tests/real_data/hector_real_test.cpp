// SPDX-License-Identifier: BSD-3-Clause
// Hector SLAM (Kohlbrecher et al. 2011) on the raw logs of Kuemmerle et al. 2009: the relation
// error of the library's default configuration, with and without odometry, against the
// 'scan matching' column of that paper (Intel 0.220 m, ACES 0.173 m, FR079 0.258 m). The bounds
// sit a little above what was measured (docs/methods/hector.md has the table); one default
// configuration for every log.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "slam2d/eval/ate.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "real_data/real_logs.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

struct HectorLog {
  const char* name;
  const char* log;
  const char* relations;
  double max_trans_mean_odometry;     // m
  double max_trans_mean_no_odometry;  // m
  double max_rot_mean_deg;            // deg, both modes
};

void PrintTo(const HectorLog& log, std::ostream* os) { *os << log.name; }

RelationErrorResult run_hector(const std::vector<LaserMessage>& scans, const std::vector<Relation>& relations,
                               bool odometry) {
  HectorSlamConfig config;
  config.prior = odometry ? MotionPrior::kOdometry : MotionPrior::kLastPose;
  HectorSlam slam(config);
  for (const LaserMessage& laser : scans) {
    HectorInputs inputs;
    if (odometry) inputs.T_odom_robot = laser.odom_pose;
    slam.add_scan(laser.scan, inputs);
  }
  EXPECT_EQ(slam.trajectory().size(), scans.size());
  return relation_error(slam.trajectory(), relations);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values.empty() ? 0.0 : values[values.size() / 2];
}

class HectorRealData : public ::testing::TestWithParam<HectorLog> {};

TEST_P(HectorRealData, RelationErrorBeatsScanMatchingOfKuemmerle2009) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const HectorLog& log = GetParam();
  const std::vector<LaserMessage> scans = test::laser_messages(test::read_log(data / log.log));
  const std::vector<Relation> relations = read_relations((data / log.relations).string());
  for (const bool odometry : {true, false}) {
    const RelationErrorResult result = run_hector(scans, relations, odometry);
    EXPECT_EQ(result.missing, 0u);
    std::vector<double> translations;
    for (const RelationError& e : result.errors) translations.push_back(e.translation);
    const double bound = odometry ? log.max_trans_mean_odometry : log.max_trans_mean_no_odometry;
    EXPECT_LT(result.translation.mean, bound) << log.name << (odometry ? " with" : " without") << " odometry";
    EXPECT_LT(median(translations), 0.05) << log.name << (odometry ? " with" : " without") << " odometry";
    EXPECT_LT(result.rotation_deg.mean, log.max_rot_mean_deg);
  }
}

// Measured (m, mean translational relation error, with / without odometry): Intel 0.018 / 0.020,
// ACES 0.054 / 0.166, FR079 0.036 / 0.035 (with odometry, before its prior: 0.020, 0.095,
// 0.035). ACES without odometry only just beats the 2009 figure: the robot turns 1.4 rad during
// a 3 s gap in the log, which only the recovery search catches.
INSTANTIATE_TEST_SUITE_P(Kuemmerle2009, HectorRealData,
                         ::testing::Values(HectorLog{"intel", "intel/intel.clf.gz", "intel/intel.relations", 0.04, 0.04, 0.4},
                                           HectorLog{"aces", "aces/aces.clf.gz", "aces/aces.relations", 0.12, 0.19, 0.6},
                                           HectorLog{"fr079", "fr079/fr079.clf.gz", "fr079/fr079.relations", 0.05, 0.05, 0.6}),
                         [](const auto& info) { return std::string(info.param.name); });

// Hector with `config` over Intel with its wheel odometry; its calibration must have found the
// odometry's systematic error.
HectorSlam calibrated_on_intel(const std::filesystem::path& data, const HectorSlamConfig& config) {
  HectorSlam slam(config);
  for (const LaserMessage& laser : test::laser_messages(test::read_log(data / "intel/intel.clf.gz"))) {
    slam.add_scan(laser.scan, HectorInputs{.T_odom_robot = laser.odom_pose});
  }
  EXPECT_TRUE(slam.calibrating());
  const OdometryCalibration& calibration = slam.odometry_calibration();
  EXPECT_GT(calibration.observations(), 1000u);
  EXPECT_NEAR(calibration.drift_per_metre(), 0.059, 0.008);
  EXPECT_NEAR(calibration.translation_scale(), 0.968, 0.015);
  EXPECT_NEAR(calibration.rotation_scale(), 0.974, 0.02);
  return slam;
}

// Intel's wheel odometry turns about 0.06 rad per metre less than the robot did and reads its
// distances 3 % long (the EKF's and the RBPF's calibrations find the same). Graph SLAM's tracker
// (Hector's matcher under the prior weighed by the odometry's learnt noise) with
// `odometry_calibration` learns that from its own matches over stretches of half a metre and
// corrects each increment before it predicts (graph SLAM's default since 2026-12-07, over 1000
// stretches, each error corrected by what of it stands out of the fit's uncertainty: here nearly
// all). Measured: drift 0.058 rad/m, scales 0.967 and 0.973; at most 10 s apart 0.0131 m (the
// odometry alone 0.0235 m).
TEST(HectorRealDataTracker, TheWeighedPriorsCalibrationFindsTheIntelOdometrysSystematicError) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const HectorSlamConfig config = GraphSlamConfig{}.tracking;
  ASSERT_TRUE(config.prior_from_motion_noise);
  ASSERT_GT(config.odometry_calibration.window, 0.0);
  const HectorSlam slam = calibrated_on_intel(data, config);
  const std::vector<Relation> relations =
      test::relations_at_most(read_relations((data / "intel/intel.relations").string()), 10.0);
  EXPECT_LT(relation_error(slam.trajectory(), relations).translation.mean, 0.0235);
}

// The same calibration under Hector's own prior (the constant one, not weighed by a learnt noise):
// the stretches are weighed by the noise model as it is, and the fit finds the same error.
// Measured (window 1000, significance 5): drift 0.058 rad/m, scales 0.969 and 0.984.
TEST(HectorRealDataTracker, TheCalibrationFindsTheIntelOdometrysSystematicErrorUnderTheConstantPrior) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  HectorSlamConfig config;
  ASSERT_FALSE(config.prior_from_motion_noise);
  ASSERT_FALSE(config.fuse_odometry);
  config.odometry_calibration.window = 1000.0;
  config.odometry_calibration.significance = 5.0;
  calibrated_on_intel(data, config);
}

// 198 s of the scans missing from t = 300 s or 700 s (the held-out hospital log has such a gap),
// the wheel odometry kept. Hector's one map pulled the first scan after the gap onto whatever place
// was nearest the odometry's prediction (Intel's odometry is 24 m and 2.7 rad off there): 3.07 m
// over all relations at 300 s, 5.00 m at 700 s. After a gap it starts a new map and searches the old
// one over the odometry's drift measured before the gap (HectorSlamConfig::relocalization).
// Measured: Intel 0.0167 / 0.0176 m, ACES 0.052 / 0.046 m (0.194 / 0.164 m without; at 700 s a
// match 5.6 m along a corridor was refused because 27 % of the new map's walls fell on the old
// map's free space, the right one's 5 %), FR079 0.036 / 0.034 m (2.07 / 0.123 m without).
TEST(HectorRealData, FindsItsPlaceInTheOldMapAfterAGapInTheScans) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const auto error_under = [&](const std::string& name, double start, bool relocalize) {
    HectorSlamConfig config;
    config.relocalization.enabled = relocalize;
    HectorSlam slam(config);
    const std::string gap = "scan-gap:every=100000,start=" + std::to_string(start) + ",duration=198";
    for (const LaserMessage& laser : test::laser_messages(test::read_log_with_fault(data / name / (name + ".clf.gz"), gap))) {
      slam.add_scan(laser.scan, HectorInputs{.T_odom_robot = laser.odom_pose});
    }
    EXPECT_EQ(slam.gap_stats().gaps, relocalize ? 1u : 0u) << name;
    return relation_error(slam.trajectory(), read_relations((data / name / (name + ".relations")).string())).translation.mean;
  };
  EXPECT_LT(error_under("intel", 300.0, true), 0.025);
  EXPECT_GT(error_under("intel", 300.0, false), 1.0) << "the gap no longer tests the search";
  EXPECT_LT(error_under("intel", 700.0, true), 0.025);
  EXPECT_LT(error_under("aces", 300.0, true), 0.08);
  EXPECT_LT(error_under("aces", 700.0, true), 0.08);
  EXPECT_LT(error_under("fr079", 300.0, true), 0.05);
  EXPECT_LT(error_under("fr079", 700.0, true), 0.05);
}

// Graph SLAM's tracker's fusion on Hector (not its default: docs/fusion_by_uncertainty.md, "Hector
// weighing its odometry"): the prior weighed by the odometry's learnt noise, heading included, and
// the retry after a poor fit within a quarter turn of a trusted increment.
HectorSlamConfig weighed_prior_and_retry() {
  HectorSlamConfig config;
  config.prior_from_motion_noise = true;
  config.recovery_residual = 0.25;
  return config;
}

// Freiburg campus, SLAM-corrected: the odometry of its FLASER lines is the corrected trajectory
// itself, exact. With the default prior, on the translation alone, nothing holds Hector's heading
// on its sparse outdoor scans (53.8 m ATE with `slam2d map`); the weighed prior holds it, and its
// retry after a poor fit keeps it because against a trusted increment the turned fit must explain
// the scan, as a rotated start must (HectorMatcherConfig::rotation_search_min_explained: 4.2 m;
// 53.5 m when the retry alone was not gated, before 2026-12-05; 7.7 m with neither gated).
// Stamped by index, as the robustness benchmark does: the log's stamps do not increase.
double freiburg_campus_ate(const std::filesystem::path& data, const HectorSlamConfig& config) {
  const test::CorrectedScans campus = test::read_corrected_flaser(data / "carmen-corrected/freiburg-campus-corrected.log.gz");
  HectorSlam slam(config);
  for (const LaserMessage& laser : campus.scans) slam.add_scan(laser.scan, HectorInputs{.T_odom_robot = laser.odom_pose});
  return absolute_trajectory_error(slam.trajectory(), campus.reference).rmse;
}

TEST(HectorRealDataTracker, TheWeighedPriorsRetryKeepsFreiburgCampussExactOdometry) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const double ate = freiburg_campus_ate(data, weighed_prior_and_retry());
  std::cout << "[ measured ] freiburg-campus, exact odometry: hector, weighed prior and retry " << ate << " m ATE\n";
  EXPECT_LT(ate, 6.0);
  EXPECT_GT(freiburg_campus_ate(data, HectorSlamConfig{}), 20.0) << "the log no longer tests the prior";
}

// FR079 at one scan a second: at t = 1000 s the wheel odometry misses 0.45 rad of a 0.62 rad turn
// in one step. With the weighed prior the retry within a quarter turn takes it back (`slam2d map`:
// 0.044 m over all relations); the defaults keep the heading 0.67 rad off (0.40 m).
TEST(HectorRealDataTracker, TheWeighedPriorsRetryTakesBackAnOdometrySlipAtOneHertz) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<LaserMessage> scans =
      test::laser_messages(test::read_log_with_fault(data / "fr079/fr079.clf.gz", "scan-rate:hz=1"));
  const std::vector<Relation> relations = read_relations((data / "fr079/fr079.relations").string());
  const auto error = [&](const HectorSlamConfig& config) {
    HectorSlam slam(config);
    for (const LaserMessage& laser : scans) slam.add_scan(laser.scan, HectorInputs{.T_odom_robot = laser.odom_pose});
    return relation_error(slam.trajectory(), relations).translation.mean;
  };
  const double weighed = error(weighed_prior_and_retry());
  std::cout << "[ measured ] fr079 at 1 Hz: hector, weighed prior and retry " << weighed << " m\n";
  EXPECT_LT(weighed, 0.07);
  EXPECT_GT(error(HectorSlamConfig{}), 0.2) << "the fault no longer tests the retry";
}

// Intel with its odometry 0.6 s ahead of the laser, the offset estimated and compensated (see
// GraphSlamRealData.IsNotTurnedAroundWhereItsOdometryIsOutOfStepInTime): where the shifted
// odometry puts a burst's turn on the scan after a pause, Hector's match from that prediction
// settled 0.9 rad off (1.12 m over all relations with `slam2d map`). Confirmed against the last
// pose (OdometryCheck::confirm), the increment over the pause loses to the scans (0.062 m; 0.039 m
// when only pauses longer than a gap were confirmed, where the RBPF stayed at 1.06 m; the clean log
// 0.018 m).
TEST(HectorRealData, ConfirmsAnIncrementOverAPauseWhereItsOdometryIsOutOfStepInTime) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<Relation> relations = read_relations((data / "intel/intel.relations").string());
  const std::vector<LaserMessage> scans = test::read_scans_out_of_step(data / "intel/intel.clf.gz", 0.6).scans;
  const auto error = [&](bool confirm) {
    HectorSlamConfig config;
    config.odometry_guard.confirm_pause = confirm ? OdometryGuardConfig{}.confirm_pause : 0.0;
    HectorSlam slam(config);
    for (const LaserMessage& laser : scans) slam.add_scan(laser.scan, HectorInputs{.T_odom_robot = laser.odom_pose});
    return relation_error(slam.trajectory(), relations).translation.mean;
  };
  const double confirmed = error(true);
  std::cout << "[ measured ] intel, odometry 0.6 s ahead: hector " << confirmed << " m\n";
  EXPECT_LT(confirmed, 0.1);
  EXPECT_GT(error(false), 0.5) << "the log no longer tests the confirmation";
}

}  // namespace
}  // namespace slam2d
