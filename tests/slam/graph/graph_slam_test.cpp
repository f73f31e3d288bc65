// SPDX-License-Identifier: BSD-3-Clause
// Graph SLAM on the simulated office: keyframe rules and chains against hand cases, the loop of
// the office run closed and the trajectory recovered within stated bounds (with and without
// odometry, with immediate closure), a false loop edge absorbed by the robust kernel, determinism;
// the hospital world's corridors, a false closure and an open axis.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/eval/ate.hpp"
#include "slam2d/eval/rpe.hpp"
#include "slam2d/sim/office_world.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "support/graph_configs.hpp"
#include "support/simulated_office.hpp"

namespace slam2d {
namespace {

const SimulatedRun& office_run() { return test::simulated_office(240.0, 7); }

GraphSlam run_graph_slam(const GraphSlamConfig& config, bool use_odometry) {
  GraphSlam slam(config);
  for (const LaserMessage* laser : laser_messages(office_run())) {
    slam.add_scan(laser->scan, use_odometry ? std::optional<SE2>(laser->odom_pose) : std::nullopt);
  }
  slam.finish();
  return slam;
}

TEST(KeyframeSelector, TakesDistanceAngleAndTime) {
  KeyframeSelector selector({.min_distance = 0.2, .min_angle = 0.2, .min_time = 5.0});
  EXPECT_TRUE(selector.is_keyframe(SE2(), 0.0));  // the first scan
  selector.accept(SE2(1.0, 1.0, 0.5), 10.0);
  EXPECT_FALSE(selector.is_keyframe(SE2(1.1, 1.1, 0.6), 11.0));   // 0.14 m, 0.1 rad, 1 s
  EXPECT_TRUE(selector.is_keyframe(SE2(1.15, 1.15, 0.5), 11.0));  // 0.21 m
  EXPECT_TRUE(selector.is_keyframe(SE2(1.0, 1.0, 0.71), 11.0));   // 0.21 rad
  EXPECT_TRUE(selector.is_keyframe(SE2(1.0, 1.0, 0.5), 15.0));    // 5 s standing still
  EXPECT_THROW(KeyframeSelector({.min_distance = -1.0}), Error);
}

TEST(LoopChains, GroupsConsecutiveCandidates) {
  const std::vector<std::size_t> candidates{2, 3, 4, 7, 8, 10, 11, 12, 13};
  using Chains = std::vector<std::pair<std::size_t, std::size_t>>;
  EXPECT_EQ(group_into_chains(candidates, 3), (Chains{{2, 5}, {10, 14}}));
  EXPECT_EQ(group_into_chains(candidates, 1), (Chains{{2, 5}, {7, 9}, {10, 14}}));
  EXPECT_TRUE(group_into_chains({}, 1).empty());
}

struct OfficeCase {
  const char* name;
  bool odometry;
  bool delayed;
  double max_ate_rmse;  // m
};
void PrintTo(const OfficeCase& c, std::ostream* os) { *os << c.name; }

class GraphSlamOffice : public ::testing::TestWithParam<OfficeCase> {};

TEST_P(GraphSlamOffice, ClosesTheLoopAndRecoversTheTrajectory) {
  GraphSlamConfig config;
  config.loop_closure.delayed = GetParam().delayed;
  const GraphSlam slam = run_graph_slam(config, GetParam().odometry);
  const SimulatedRun& run = office_run();
  const Trajectory trajectory = slam.trajectory();
  ASSERT_EQ(trajectory.size(), run.truth.size());
  EXPECT_GT(slam.stats().loop_closures, 0u);
  EXPECT_GT(slam.stats().keyframes, 50u);
  EXPECT_EQ(slam.graph().size(), slam.stats().keyframes);
  const AteResult ate = absolute_trajectory_error(trajectory, run.truth);
  const AteResult odometry_ate = absolute_trajectory_error(test::odometry_of(run), run.truth);
  EXPECT_LT(ate.rmse, GetParam().max_ate_rmse) << "max " << ate.max;
  EXPECT_LT(ate.rmse, 0.2 * odometry_ate.rmse);
  double worst_heading = 0.0;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const SE2 aligned = ate.T_reference_estimate * trajectory[i].pose;
    worst_heading = std::max(worst_heading, std::abs(angle_difference(aligned.theta(), run.truth[i].pose.theta())));
  }
  EXPECT_LT(worst_heading, 0.02);
}

INSTANTIATE_TEST_SUITE_P(Modes, GraphSlamOffice,
                         ::testing::Values(OfficeCase{"odometry", true, true, 0.05},
                                           OfficeCase{"no_odometry", false, true, 0.05},
                                           OfficeCase{"immediate", true, false, 0.05}),
                         [](const auto& info) { return std::string(info.param.name); });

// Seed 1 drives along the office corridor early on; without solution remapping the tracker stalled
// there for 14 s (ATE 1.74 m) while the robot drove on.
TEST(GraphSlam, TracksAlongTheCorridorWithTheOdometry) {
  SimulationConfig simulation;
  simulation.duration = 60.0;
  simulation.seed = 1;
  const SimulatedRun run = simulate(simulation);
  GraphSlam slam;
  for (const LaserMessage* laser : laser_messages(run)) slam.add_scan(laser->scan, laser->odom_pose);
  slam.finish();
  EXPECT_LT(absolute_trajectory_error(slam.trajectory(), run.truth).rmse, 0.05);
}

// The hospital world (sim/hospital_world.hpp) for 600 s: at 528 s the robot comes down a side
// corridor to the corner it started from, whose first scans saw the corner's two walls from the
// main corridor. Its scan shows the other corner of the junction, an L that fits the mapped corner
// from behind it, 3.4 m off: that closure bent the map to 1.19 m ATE, worse than the odometry it
// was given (0.83 m). A large correction whose scan sees the map's walls from behind is refused
// (slam/graph/loop_closure.hpp).
TEST(GraphSlam, ClosesNoLoopOntoACornerSeenFromBehindIt) {
  const SimulatedRun run = simulate(test::hospital_simulation(600.0));
  GraphSlam slam;
  for (const LaserMessage* laser : laser_messages(run)) slam.add_scan(laser->scan, laser->odom_pose);
  slam.finish();
  const double ate = absolute_trajectory_error(slam.trajectory(), run.truth).rmse;
  const double odometry_ate = absolute_trajectory_error(test::odometry_of(run), run.truth).rmse;
  RecordProperty("ate_rmse_mm", static_cast<int>(1000 * ate));
  RecordProperty("odometry_ate_rmse_mm", static_cast<int>(1000 * odometry_ate));
  EXPECT_GT(slam.stats().loop_closures, 0u);
  EXPECT_LT(ate, 0.5 * odometry_ate);
}

// The hospital world for 700 s: 24 m of its corridors show the tracker no edge within its 25 m,
// and its map holds the far walls as dots a beam apart from where they were first seen, which pin
// the next scans there: the matched motion fell up to 0.26 m short over 4 m, where the odometry
// errs by a centimetre. The translation the scan's own geometry leaves open is the prediction's
// (HectorMatcherConfig::scan_degeneracy_ratio): the error over 10 s under the odometry's, where
// without it it was over.
TEST(GraphSlam, LeavesTheAxisOfACorridorWithoutEdgesToTheOdometry) {
  const SimulatedRun run = simulate(test::hospital_simulation(700.0));
  const RpeConfig ten_seconds{.window = RpeWindow::kTime, .delta = 10.0};
  const auto error = [&](const GraphSlamConfig& config) {
    GraphSlam slam(config);
    for (const LaserMessage* laser : laser_messages(run)) slam.add_scan(laser->scan, laser->odom_pose);
    slam.finish();
    return relative_pose_error(slam.trajectory(), run.truth, ten_seconds).translation.mean;
  };
  GraphSlamConfig closed_axis;
  closed_axis.tracking.matcher.scan_degeneracy_ratio = 0.0;
  const double odometry = relative_pose_error(test::odometry_of(run), run.truth, ten_seconds).translation.mean;
  const double open = error(GraphSlamConfig{});
  const double closed = error(closed_axis);
  RecordProperty("rpe10_mm", static_cast<int>(1000 * open));
  RecordProperty("rpe10_without_open_axis_mm", static_cast<int>(1000 * closed));
  RecordProperty("odometry_rpe10_mm", static_cast<int>(1000 * odometry));
  EXPECT_LT(open, 0.8 * odometry);
  EXPECT_GT(closed, odometry);
}

TEST(GraphSlam, RobustKernelAbsorbsAFalseLoopEdge) {
  const GraphSlam slam = run_graph_slam({}, true);
  PoseGraph graph = slam.graph();
  const SimulatedRun& run = office_run();
  // The last keyframe claimed to sit 3 m and 90 degrees off the first one, as confidently as the
  // sequential edges (sigma 1 mm against their 2 mm).
  PoseGraphEdge wrong;
  wrong.from = 0;
  wrong.to = static_cast<int>(graph.size() - 1);
  wrong.T_from_to = graph.poses.front().between(graph.poses.back()) * SE2(3.0, 0.0, std::numbers::pi / 2);
  wrong.information = Eigen::Matrix3d::Identity() * 1e6;
  wrong.robust = true;
  graph.edges.push_back(wrong);
  PoseGraph plain = graph;
  plain.edges.back().robust = false;
  SparsePoseAdjustment(slam.config().back_end).optimize(graph);
  SparsePoseAdjustment(SparsePoseAdjustmentConfig{}).optimize(plain);
  const auto keyframe_error = [&](const PoseGraph& g) {
    Trajectory estimate, truth;
    for (const Keyframe& keyframe : slam.keyframes()) {
      estimate.push_back(keyframe.stamp, g.poses[keyframe.node]);
      truth.push_back(keyframe.stamp, run.truth[keyframe.scan].pose);
    }
    return absolute_trajectory_error(estimate, truth).rmse;
  };
  EXPECT_LT(keyframe_error(graph), 0.05);
  EXPECT_GT(keyframe_error(plain), 0.3);  // without the kernel the false edge bends the map
}

// The office run with the scans of [100 s, 130 s) missing and an odometry whose heading drifts by
// 0.05 rad per metre driven (Intel's is 0.06): across the gap it is metres and a radian off, as far
// as it drifted over any 30 s before. A 30 s pause is a gap (past gap.seconds and 20 intervals),
// after which graph SLAM finds its place again. The same scans with every stamp ten times later (a
// scan a second) and 1.5 s missing, a pause of 15 intervals, are no gap. With the true poses as
// the odometry the gap is tracked through.
TEST(GraphSlam, CountsAGapByTheScanIntervalAndFindsItsPlaceAgain) {
  const SimulatedRun& run = office_run();
  const std::vector<const LaserMessage*> lasers = laser_messages(run);
  const std::vector<SE2> drifting = test::odometry_with_heading_drift(run, 0.05);
  const auto map_with_pause = [&](double from, double to, double stamp_scale, bool exact = false) {
    GraphSlam slam;
    Trajectory truth;
    for (std::size_t i = 0; i < lasers.size(); ++i) {
      const double t = lasers[i]->scan.stamp;
      if (t >= from && t < to) continue;
      LaserScan scan = lasers[i]->scan;
      scan.stamp = stamp_scale * t;
      slam.add_scan(scan, exact ? run.truth[i].pose : drifting[i]);
      truth.push_back(scan.stamp, run.truth[i].pose);
    }
    slam.finish();
    return std::tuple{slam.stats().gaps, absolute_trajectory_error(slam.trajectory(), truth).rmse,
                      slam.stats().gaps_tracked_through};
  };
  const auto [gaps, rmse, tracked] = map_with_pause(100.0, 130.0, 1.0);
  EXPECT_EQ(gaps, 1u);
  EXPECT_EQ(tracked, 0u);
  EXPECT_LT(rmse, 0.1);
  EXPECT_EQ(std::get<0>(map_with_pause(100.0, 101.5, 10.0)), 0u);
  // The true poses as the odometry: the window over its drift stays within the tracker's reach,
  // and the tracker keeps its map across the gap.
  const auto [exact_gaps, exact_rmse, exact_tracked] = map_with_pause(100.0, 130.0, 1.0, true);
  EXPECT_EQ(exact_gaps, 1u);
  EXPECT_EQ(exact_tracked, 1u);
  EXPECT_LT(exact_rmse, 0.05);
}

TEST(GraphSlam, IsDeterministic) {
  GraphSlamConfig config;
  const GraphSlam a = run_graph_slam(config, true);
  const GraphSlam b = run_graph_slam(config, true);
  ASSERT_EQ(a.trajectory().size(), b.trajectory().size());
  for (std::size_t i = 0; i < a.trajectory().size(); ++i) EXPECT_EQ(a.trajectory()[i].pose, b.trajectory()[i].pose);
}

TEST(GraphSlam, RejectsBadConfiguration) {
  EXPECT_THROW(GraphSlam({.max_range = 0.0}), Error);
  GraphSlamConfig config;
  config.loop_closure.min_chain_size = 0;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.sequential_sigma_translation = 0.0;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.tracking.max_range = -1.0;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.gap.seconds = 0.0;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.gap.periods = 0.5;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.gap.speed = -1.0;
  EXPECT_THROW(GraphSlam{config}, Error);
}

// Lifelong mapping: the office's corridor ring driven three times. With the keyframe budget on (the
// default), the laps after the first are registered against it and their keyframes drop their
// points: the keyframes that keep data stop growing after the first lap while the graph keeps every
// node, and the trajectory stays as good as with every keyframe kept.
struct RingLaps {
  GraphSlamStats stats;
  std::size_t held_after_first_lap = 0;
  std::size_t keyframes_after_first_lap = 0;
  std::size_t held_at_end = 0;
  std::size_t live_nodes = 0;  // nodes with an edge at the end: the back end's unknowns
  double ate_rmse = 0.0;
};

std::size_t held_keyframes(const GraphSlam& slam) {
  return static_cast<std::size_t>(std::count_if(slam.keyframes().begin(), slam.keyframes().end(),
                                                [](const Keyframe& k) { return !k.released; }));
}

const SimulatedRun& ring_run() {
  static const SimulatedRun run = [] {
    World world = make_office_world();
    world.route = {{4.0, 6.0}, {20.0, 6.0}, {20.0, 12.0}, {4.0, 12.0}};  // 44 m round
    SimulationConfig config;
    config.duration = 250.0;  // three laps at 0.6 m/s
    config.seed = 3;
    return simulate(config, world);
  }();
  return run;
}

RingLaps drive_ring(const GraphSlamConfig& config) {
  const SimulatedRun& run = ring_run();
  const std::vector<const LaserMessage*> lasers = laser_messages(run);
  GraphSlam slam(config);
  RingLaps laps;
  double driven = 0.0;
  for (std::size_t i = 0; i < lasers.size(); ++i) {
    slam.add_scan(lasers[i]->scan, lasers[i]->odom_pose);
    if (i > 0) driven += (run.truth[i].pose.translation() - run.truth[i - 1].pose.translation()).norm();
    if (laps.keyframes_after_first_lap == 0 && driven >= 44.0) {
      laps.keyframes_after_first_lap = slam.keyframes().size();
      laps.held_after_first_lap = held_keyframes(slam);
    }
  }
  slam.finish();
  laps.stats = slam.stats();
  laps.held_at_end = held_keyframes(slam);
  std::vector<bool> live(slam.graph().size(), false);
  for (const PoseGraphEdge& edge : slam.graph().edges) {
    live[static_cast<std::size_t>(edge.from)] = true;
    live[static_cast<std::size_t>(edge.to)] = true;
  }
  laps.live_nodes = static_cast<std::size_t>(std::count(live.begin(), live.end(), true));
  laps.ate_rmse = absolute_trajectory_error(slam.trajectory(), run.truth).rmse;
  return laps;
}

TEST(GraphSlamLifelong, KeyframesHoldingDataStopGrowingAfterTheFirstLap) {
  GraphSlamConfig keep_all;
  keep_all.keyframes.redundant_radius = 0.0;
  const RingLaps all = drive_ring(keep_all);
  const RingLaps lifelong = drive_ring({});  // the budget is on by default
  EXPECT_EQ(all.stats.released_keyframes, 0u);
  EXPECT_EQ(all.held_at_end, all.stats.keyframes);
  EXPECT_GT(lifelong.stats.keyframes, 2.5 * lifelong.keyframes_after_first_lap);  // the graph keeps every node
  EXPECT_EQ(lifelong.held_at_end + lifelong.stats.released_keyframes, lifelong.stats.keyframes);
  // What still grows: the first keyframes of lap 2 (before its first closure goes in, delayed) and
  // the last ones, which the loop closer may still need (199, 275 and 609 keyframes when written).
  EXPECT_LT(lifelong.held_at_end, 1.5 * lifelong.held_after_first_lap)
      << lifelong.held_after_first_lap << " after the first lap of " << lifelong.stats.keyframes;
  EXPECT_GT(lifelong.stats.released_keyframes, 0.6 * (lifelong.stats.keyframes - lifelong.keyframes_after_first_lap));
  EXPECT_LT(lifelong.ate_rmse, std::max(0.05, 1.2 * all.ate_rmse)) << "all kept: " << all.ate_rmse;
}

// keyframes.merge_released: a released keyframe's node merges into its witness's, so the back end's
// unknowns stop growing after the first lap too, and the trajectory stays as good.
TEST(GraphSlamLifelong, MergedNodesStopTheGraphGrowingAfterTheFirstLap) {
  GraphSlamConfig merging;
  merging.keyframes.merge_released = true;
  const RingLaps kept = drive_ring({});
  const RingLaps merged = drive_ring(merging);
  EXPECT_EQ(kept.stats.merged_nodes, 0u);
  EXPECT_EQ(kept.live_nodes, kept.stats.keyframes);
  ASSERT_GT(merged.stats.released_keyframes, 0u);
  EXPECT_EQ(merged.stats.merged_nodes, merged.stats.released_keyframes);
  EXPECT_EQ(merged.live_nodes + merged.stats.merged_nodes, merged.stats.keyframes);
  EXPECT_LT(merged.live_nodes, 1.5 * merged.keyframes_after_first_lap)
      << merged.keyframes_after_first_lap << " after the first lap of " << merged.stats.keyframes;
  EXPECT_LT(merged.ate_rmse, std::max(0.05, 1.2 * kept.ate_rmse)) << "every node kept: " << kept.ate_rmse;
}

// The back end's schedule: a closure that closes a new loop is optimised at once (Karto's); one
// along a place closed before waits while the closures waiting agree with the estimate. On the
// ring's three laps (44 m round, few closures, each lap's first one a new loop by the graph's
// path) that spares at least one optimisation, and the trajectory is as good. The ten passes of
// the real logs are in docs/methods/graph_slam.md; FR079 in tests/real_data/graph_real_test.cpp.
TEST(GraphSlamSchedule, DefersAClosureOfALaterLapThatAgreesWithTheMap) {
  // The ring's odometry errs by a scale and a heading bias, which make its laps' closures; the
  // tracker's calibration takes most of that out (no closure then waits), so both runs go without.
  GraphSlamConfig every_closure = test::graph_without_calibration();
  every_closure.defer_agreeing_closures = false;
  const RingLaps karto = drive_ring(every_closure);
  const RingLaps deferred = drive_ring(test::graph_without_calibration());  // deferral on by default
  EXPECT_EQ(karto.stats.deferred_optimizations, 0u);
  ASSERT_GT(karto.stats.loop_closures, 5u);
  ASSERT_GT(deferred.stats.loop_closures, 5u);
  EXPECT_GE(deferred.stats.deferred_optimizations, 1u);
  EXPECT_LT(deferred.stats.optimizations, karto.stats.optimizations);
  EXPECT_LT(deferred.ate_rmse, std::max(0.05, 1.2 * karto.ate_rmse)) << "after every closure: " << karto.ate_rmse;
}

// A closure whose cycle along the graph is short (local_reach) is optimised over the nodes within
// that cycle of its ends, the rest held: on the ring's later laps such optimisations happen, and
// the trajectory (finish() optimises the whole graph) is as good as with every optimisation of the
// whole graph. The ten passes of the real logs:
// docs/methods/graph_slam.md, "The back end's schedule".
TEST(GraphSlamSchedule, AShortCycleIsOptimisedOverItsNeighbourhood) {
  GraphSlamConfig whole;
  whole.local_reach = 0.0;
  const RingLaps all = drive_ring(whole);
  const RingLaps local = drive_ring({});  // on by default
  EXPECT_EQ(all.stats.local_optimizations, 0u);
  ASSERT_GT(local.stats.loop_closures, 5u);
  EXPECT_GE(local.stats.local_optimizations, 1u);
  EXPECT_LE(local.stats.local_optimizations, local.stats.optimizations);
  EXPECT_LT(local.ate_rmse, std::max(0.05, 1.2 * all.ate_rmse)) << "whole graph: " << all.ate_rmse;
}

TEST(GraphSlamLifelong, RejectsOutOfRangeBudgets) {
  GraphSlamConfig config;
  config.keyframes.redundant_radius = -0.5;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.keyframes.redundant_angle = -0.1;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.keyframes.redundant_radius = 0.5;
  config.keyframes.redundant_angle = 0.0;  // would release nothing
  EXPECT_THROW(GraphSlam{config}, Error);
  config.keyframes.redundant_angle = 0.5;
  EXPECT_NO_THROW(GraphSlam{config});
}

}  // namespace
}  // namespace slam2d
