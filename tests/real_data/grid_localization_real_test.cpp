// SPDX-License-Identifier: BSD-3-Clause
// The Markov grid and the hybrid (Gutmann et al. 1998) on the Intel Research Lab log, as
// localization_real_test.cpp does for the EKF and MCL: the map from the SLAM-corrected log, the
// raw log localized in it. The reference is the EKF tracked from the raw log's known first pose
// (0.037 m from the Kuemmerle 2009 relations, LocalizationRealData.EkfTracksIntelFromAKnownStart).
// Each method tracks from the known start at its relation error; localizes globally at the right
// place (no step reported localized away from the reference); and, kidnapped by 5 m and 90 deg,
// is back at the reference and stays there, where the EKF alone never comes back; with spurious
// readings that lead the grid astray, the hybrid stays with the robot. Bounds sit a
// little above what was measured (docs/methods/localization.md, "Figures").

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/hybrid.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/session.hpp"
#include "slam2d/sim/fault_injection.hpp"
#include "real_data/real_logs.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

const SE2 kIntelStart(-0.0718, -0.1626, 0.2200);  // the raw log's first scan in the corrected log's map

const LocalizationMap& intel_map(const std::filesystem::path& data) {
  static const LocalizationMap map = [&] {
    OccupancyGrid grid(OccupancyGridConfig{.resolution = 0.05});
    CarmenReader reader((data / "intel" / "intel-corrected.log.gz").string());
    while (auto message = reader.next()) {
      if (const auto* laser = std::get_if<LaserMessage>(&*message)) grid.integrate_scan(laser->scan, laser->odom_pose);
    }
    return LocalizationMap(grid.to_occupancy_map());
  }();
  return map;
}

// The localizer over the first `max_scans` front-laser scans of the raw Intel log.
LocalizationSession& localize(LocalizationSession& session, const std::filesystem::path& data, std::size_t max_scans) {
  CarmenReader reader((data / "intel" / "intel.clf.gz").string());
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    session.add(laser->odom_pose, laser->scan);
    if (session.summary().scans == max_scans) break;
  }
  return session;
}

// The EKF from the known start over the first `scans` scans (made once per length).
const Trajectory& reference(const std::filesystem::path& data, std::size_t scans) {
  static std::vector<std::pair<std::size_t, Trajectory>> made;
  for (const auto& [length, trajectory] : made) {
    if (length == scans) return trajectory;
  }
  EkfLocalization ekf(intel_map(data));
  ekf.initialize(kIntelStart, covariance_from_sigmas(0.3, 0.3, 0.2));
  LocalizationSession session(ekf);
  made.emplace_back(scans, localize(session, data, scans).trajectory());
  return made.back().second;
}

// m, distance to the reference at each scan.
std::vector<double> errors(const Trajectory& trajectory, const Trajectory& reference) {
  std::vector<double> result;
  for (std::size_t i = 0; i < trajectory.size() && i < reference.size(); ++i) {
    result.push_back((trajectory[i].pose.translation() - reference[i].pose.translation()).norm());
  }
  return result;
}

double relation_error_mean(const Trajectory& trajectory, const std::filesystem::path& data, double from) {
  std::vector<Relation> kept;
  for (const Relation& r : read_relations((data / "intel" / "intel.relations").string())) {
    if (r.stamp_from >= from && r.stamp_to >= from && r.stamp_from <= trajectory.back().stamp &&
        r.stamp_to <= trajectory.back().stamp) {
      kept.push_back(r);
    }
  }
  EXPECT_GT(kept.size(), 100u);
  return relation_error(trajectory, kept).translation.mean;
}

// Steps reported localized more than `tolerance` m from the reference.
std::size_t wrong_localized(const LocalizationSession& session, const Trajectory& reference, double tolerance) {
  const std::vector<double> e = errors(session.trajectory(), reference);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < e.size(); ++i) wrong += session.localized()[i] && e[i] > tolerance ? 1 : 0;
  return wrong;
}

// s from `after` (absolute stamp) until the error is below `tolerance` and stays below it to the
// end of the run; nullopt if it is not below at the end.
std::optional<double> back_for_good(const Trajectory& trajectory, const Trajectory& reference, double after, double tolerance) {
  const std::vector<double> e = errors(trajectory, reference);
  std::optional<double> since;
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (trajectory[i].stamp < after) continue;
    if (e[i] > tolerance) {
      since.reset();
    } else if (!since) {
      since = trajectory[i].stamp - after;
    }
  }
  return since;
}

TEST(GridLocalizationRealData, MarkovAndHybridTrackIntelFromAKnownStart) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  constexpr std::size_t kScans = 2500;  // 500 s
  const Trajectory& ekf = reference(data, kScans);
  MarkovGridLocalization markov(intel_map(data));
  markov.initialize(kIntelStart, covariance_from_sigmas(0.3, 0.3, 0.2));
  LocalizationSession markov_run(markov);
  localize(markov_run, data, kScans);
  HybridLocalization hybrid(intel_map(data));
  hybrid.initialize(kIntelStart, covariance_from_sigmas(0.3, 0.3, 0.2));
  LocalizationSession hybrid_run(hybrid);
  localize(hybrid_run, data, kScans);
  for (const LocalizationSession* run : {&markov_run, &hybrid_run}) {
    SCOPED_TRACE(run == &markov_run ? "markov" : "hybrid");
    const std::vector<double> e = errors(run->trajectory(), ekf);
    ASSERT_EQ(e.size(), kScans);
    double largest = 0.0;
    for (const double x : e) largest = std::max(largest, x);
    EXPECT_LT(largest, 0.3);  // measured: markov 0.21 m; the hybrid tracks with its EKF, 0 m
    EXPECT_GT(static_cast<double>(run->summary().localized_scans), 0.95 * kScans);
  }
  EXPECT_LT(relation_error_mean(markov_run.trajectory(), data, markov_run.trajectory().front().stamp), 0.045);  // measured 0.036 m
  EXPECT_LT(relation_error_mean(hybrid_run.trajectory(), data, hybrid_run.trajectory().front().stamp), 0.03);  // measured 0.021 m
}

TEST(GridLocalizationRealData, MarkovAndHybridLocalizeIntelGloballyAtTheRightPlace) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  constexpr std::size_t kScans = 1500;  // 300 s
  const Trajectory& ekf = reference(data, kScans);
  MarkovGridLocalization markov(intel_map(data));
  markov.initialize_global();
  LocalizationSession markov_run(markov);
  localize(markov_run, data, kScans);
  HybridLocalization hybrid(intel_map(data));
  hybrid.initialize_global();
  LocalizationSession hybrid_run(hybrid);
  localize(hybrid_run, data, kScans);
  for (const LocalizationSession* run : {&markov_run, &hybrid_run}) {
    SCOPED_TRACE(run == &markov_run ? "markov" : "hybrid");
    ASSERT_TRUE(run->summary().converged_at_s.has_value());
    EXPECT_LT(*run->summary().converged_at_s, 50.0);  // measured: markov 36.1 s, hybrid 41.3 s
    EXPECT_EQ(wrong_localized(*run, ekf, 0.5), 0u) << "localized steps away from the known-start run";
    EXPECT_GT(run->summary().localized_scans, 1200u);  // measured 1315, 1290
  }
}

TEST(GridLocalizationRealData, MarkovAndHybridComeBackAfterAKidnapWhereTheEkfDoesNot) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  constexpr std::size_t kScans = 1500;
  const Trajectory& ekf_reference = reference(data, kScans);
  const Kidnap kidnap{.at = 150.0, .by = SE2(5.0, 0.0, deg_to_rad(90.0))};
  const auto recovery = [&](Localizer& localizer) {
    LocalizationSession session(localizer, kidnap);
    localize(session, data, kScans);
    const Trajectory& trajectory = session.trajectory();
    const double kidnapped = trajectory.front().stamp + kidnap.at;
    // The kidnap did move the estimate away from the reference.
    const std::vector<double> e = errors(trajectory, ekf_reference);
    double largest_after = 0.0;
    for (std::size_t i = 0; i < e.size(); ++i) {
      if (trajectory[i].stamp >= kidnapped) largest_after = std::max(largest_after, e[i]);
    }
    EXPECT_GT(largest_after, 3.0);  // measured 6.9 m (markov), 8.7 m (hybrid), 18.3 m (ekf)
    return back_for_good(trajectory, ekf_reference, kidnapped, 0.5);
  };
  MarkovGridLocalization markov(intel_map(data));
  markov.initialize(kIntelStart, covariance_from_sigmas(0.3, 0.3, 0.2));
  const std::optional<double> markov_back = recovery(markov);
  ASSERT_TRUE(markov_back.has_value());
  EXPECT_LT(*markov_back, 5.0);  // measured 1.0 s
  HybridLocalization hybrid(intel_map(data));
  hybrid.initialize(kIntelStart, covariance_from_sigmas(0.3, 0.3, 0.2));
  const std::optional<double> hybrid_back = recovery(hybrid);
  ASSERT_TRUE(hybrid_back.has_value());
  EXPECT_LT(*hybrid_back, 5.0);  // measured 1.6 s
  EkfLocalization ekf(intel_map(data));
  ekf.initialize(kIntelStart, covariance_from_sigmas(0.3, 0.3, 0.2));
  EXPECT_FALSE(recovery(ekf).has_value()) << "the EKF alone has no way back";
}


// The hybrid on Intel with 10 % spurious short and 10 % spurious max-range readings (the
// localization benchmark's `spurious`), over the whole log. Such readings lead the coarse grid
// astray (alone it is lost a third of the time there), and a grid localized at a wrong place used
// to reset the tracking EKF to it: 32 % of the scans more than 1 m from the reference (mean 4.2 m,
// 31 handovers). The grid now takes over only where the scan fits the map significantly better at
// its pose: measured 0.2 % (mean 0.031 m, 2 handovers).
TEST(GridLocalizationRealData, HybridKeepsTrackingWhereSpuriousReadingsLeadTheGridAstray) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  constexpr std::size_t kScans = 13631;  // the whole log
  std::vector<SensorMessage> messages = test::read_log(data / "intel" / "intel.clf.gz");
  apply_faults({parse_fault("spurious-short:p=0.1"), parse_fault("spurious-max:p=0.1")}, messages, 1);
  HybridLocalization hybrid(intel_map(data));
  hybrid.initialize(kIntelStart, covariance_from_sigmas(0.3, 0.3, 0.2));
  LocalizationSession session(hybrid);
  for (const SensorMessage& message : messages) {
    const auto* laser = std::get_if<LaserMessage>(&message);
    if (laser != nullptr && laser->type != "RLASER") session.add(laser->odom_pose, laser->scan);
  }
  ASSERT_EQ(session.trajectory().size(), kScans);
  const std::vector<double> e = errors(session.trajectory(), reference(data, kScans));
  const double far = static_cast<double>(std::count_if(e.begin(), e.end(), [](double error) { return error > 1.0; }));
  EXPECT_LT(far / static_cast<double>(e.size()), 0.02);
  EXPECT_LT(std::accumulate(e.begin(), e.end(), 0.0) / static_cast<double>(e.size()), 0.1);
  EXPECT_LE(hybrid.handovers(), 5u);
}

}  // namespace
}  // namespace slam2d
