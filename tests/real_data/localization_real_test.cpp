// Localization on the Intel Research Lab log (Kuemmerle et al. 2009): the map is built from the
// SLAM-corrected log (scans at their corrected poses, as `slam2d map --method odometry` does),
// then the raw log is localized in it. The EKF tracks the first 5000 scans from a known start
// (the map-frame pose of the raw log's first scan, found once by global MCL; see
// docs/methods/localization.md), scored by the relation error; MCL localizes globally within the
// first minute and is then as accurate. Bounds sit a little above what was measured.

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/eval/relation_error.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/localization/session.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

OccupancyMap map_from_corrected_log(const std::string& path) {
  OccupancyGrid grid(OccupancyGridConfig{.resolution = 0.05});
  CarmenReader reader(path);
  while (auto message = reader.next()) {
    if (const auto* laser = std::get_if<LaserMessage>(&*message)) grid.integrate_scan(laser->scan, laser->odom_pose);
  }
  return grid.to_occupancy_map();
}

// Runs the localizer over the first `max_scans` front-laser scans of the raw log.
LocalizationSession& localize(LocalizationSession& session, const std::string& path, std::size_t max_scans) {
  CarmenReader reader(path);
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    session.add(laser->odom_pose, laser->scan);
    if (session.summary().scans == max_scans) break;
  }
  return session;
}

// Relation error over the relations whose both stamps lie in [from, to] (absolute stamps).
RelationErrorResult error_between(const Trajectory& trajectory, const std::vector<Relation>& relations, double from, double to) {
  std::vector<Relation> kept;
  for (const Relation& r : relations) {
    if (r.stamp_from >= from && r.stamp_to >= from && r.stamp_from <= to && r.stamp_to <= to) kept.push_back(r);
  }
  return relation_error(trajectory, kept);
}

const LocalizationMap& intel_map(const std::filesystem::path& data) {
  static const LocalizationMap map(map_from_corrected_log((data / "intel" / "intel-corrected.log.gz").string()));
  return map;
}

TEST(LocalizationRealData, EkfTracksIntelFromAKnownStart) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const LocalizationMap& map = intel_map(data);
  EkfLocalization ekf(map);
  ekf.initialize(SE2(-0.0718, -0.1626, 0.2200), covariance_from_sigmas(0.3, 0.3, 0.2));
  LocalizationSession session(ekf);
  localize(session, (data / "intel" / "intel.clf.gz").string(), 5000);
  const Trajectory& trajectory = session.trajectory();
  EXPECT_EQ(session.summary().lost_events, 0u);
  EXPECT_EQ(session.summary().localized_scans, session.summary().scans);
  const RelationErrorResult error =
      error_between(trajectory, read_relations((data / "intel" / "intel.relations").string()), trajectory.front().stamp,
                    trajectory.back().stamp);
  ASSERT_GT(error.relations, 500u);
  EXPECT_LT(error.translation.mean, 0.05);  // measured 0.037 m over the whole log
  EXPECT_LT(error.translation.max, 0.3);
  EXPECT_LT(error.rotation_deg.mean, 1.0);
}

TEST(LocalizationRealData, MclLocalizesIntelGlobally) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const LocalizationMap& map = intel_map(data);
  MonteCarloLocalization mcl(map, MclConfig{.max_particles = 20000, .seed = 1});
  mcl.initialize_global();
  LocalizationSession session(mcl);
  localize(session, (data / "intel" / "intel.clf.gz").string(), 2500);
  ASSERT_TRUE(session.summary().converged_at_s.has_value());
  EXPECT_LT(*session.summary().converged_at_s, 60.0);  // measured 28 s
  const Trajectory& trajectory = session.trajectory();
  const double from = trajectory.front().stamp + *session.summary().converged_at_s + 10.0;
  const RelationErrorResult error =
      error_between(trajectory, read_relations((data / "intel" / "intel.relations").string()), from, trajectory.back().stamp);
  ASSERT_GT(error.relations, 100u);
  EXPECT_LT(error.translation.mean, 0.08);
  EXPECT_LT(error.rotation_deg.mean, 1.5);
}

}  // namespace
}  // namespace slam2d
