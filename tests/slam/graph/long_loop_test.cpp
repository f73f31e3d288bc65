// SPDX-License-Identifier: BSD-3-Clause
// Loops that close late: the drift model against hand cases, the graph paths it runs on, and two
// simulated loops the searches of loop_closure.hpp must close. The worlds are the office scaled
// up (wider corridors, longer legs) seen by a short-range laser (8-10 m), so that the tracker
// cannot see the start again from afar; the laser is blinded over part of the lap (sun, glass:
// every beam reads "no return") while the wheel odometry, with a scale error and a heading bias,
// carries the estimate: the drift that leaves is what the loop closure must remove.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <variant>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/sim/office_world.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "support/graph_configs.hpp"

namespace slam2d {
namespace {

struct BlindedLoop {
  double world_scale = 3.0;     // 1: the office world's walls and route scaled by this
  double duration = 140.0;      // s
  double blind_from = 40.0;     // s: the laser reads nothing from here ...
  double blind_until = 60.0;    // s: ... to here
  double heading_bias = 0.003;  // rad per m, of the odometry
  double speed = 1.2;           // m/s
  double laser_range = 8.0;     // m
};

// One lap of the office's corridor ring (the start is revisited only at the end of the lap).
SimulatedRun simulate_blinded_loop(const BlindedLoop& loop) {
  World world = make_office_world();
  for (WallSegment& wall : world.walls) {
    wall.a *= loop.world_scale;
    wall.b *= loop.world_scale;
  }
  world.bounds = Eigen::AlignedBox2d(world.bounds.min() * loop.world_scale, world.bounds.max() * loop.world_scale);
  world.route = {{4.0, 6.0}, {20.0, 6.0}, {20.0, 12.0}, {4.0, 12.0}};
  for (Eigen::Vector2d& point : world.route) point *= loop.world_scale;
  SimulationConfig config;
  config.duration = loop.duration;
  config.seed = 5;
  config.speed = loop.speed;
  config.laser.range_max = loop.laser_range;
  config.odometry.scale_error = 0.05;
  config.odometry.heading_bias = loop.heading_bias;
  SimulatedRun run = simulate(config, world);
  for (SensorMessage& message : run.messages) {
    auto* laser = std::get_if<LaserMessage>(&message);
    if (laser == nullptr || laser->scan.stamp < loop.blind_from || laser->scan.stamp >= loop.blind_until) continue;
    for (double& range : laser->scan.ranges) range = laser->scan.range_max;
  }
  return run;
}

// The scans [0, scans) fed with their odometry, then finish().
GraphSlam run_graph_slam(const SimulatedRun& run, const GraphSlamConfig& config, std::size_t scans) {
  GraphSlam slam(config);
  const std::vector<const LaserMessage*> lasers = laser_messages(run);
  for (std::size_t i = 0; i < scans && i < lasers.size(); ++i) slam.add_scan(lasers[i]->scan, lasers[i]->odom_pose);
  slam.finish();
  return slam;
}

// How far the last pose is from the truth, both taken relative to the first pose (m).
double end_error(const GraphSlam& slam, const SimulatedRun& run) {
  const Trajectory estimate = slam.trajectory();
  const SE2 estimated = estimate[0].pose.between(estimate[estimate.size() - 1].pose);
  const SE2 truth = run.truth[0].pose.between(run.truth[estimate.size() - 1].pose);
  return (estimated.translation() - truth.translation()).norm();
}

bool is_loop_edge(const PoseGraphEdge& edge) { return edge.to - edge.from > 1; }

TEST(DriftModel, GrowsWithDistanceAndTurn) {
  const DriftModel model{.translation_per_metre = 0.02, .rotation_per_metre = 0.001, .rotation_per_radian = 0.01};
  const Drift drift = drift_along({.distance = 100.0, .turned = 5.0}, model);
  EXPECT_DOUBLE_EQ(drift.translation, 2.0);       // 0.02 x 100
  EXPECT_DOUBLE_EQ(drift.rotation, 0.1 + 0.05);   // 0.001 x 100 + 0.01 x 5
  const Drift none = drift_along({}, model);
  EXPECT_EQ(none.translation, 0.0);
  EXPECT_EQ(none.rotation, 0.0);
  GraphSlamConfig config;
  config.loop_closure.drift.translation_per_metre = -0.01;
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.loop_closure.large.confirm_max_distance = 0.1;  // below confirm_min_distance
  EXPECT_THROW(GraphSlam{config}, Error);
  config = {};
  config.loop_closure.large.global_interval = 0;
  EXPECT_THROW(GraphSlam{config}, Error);
}

// A square of four 10 m sides (sequential edges, each turning 90 deg at its end) and a loop edge
// from node 4 back to node 0: the loop edge shortcuts the way round.
TEST(GraphPaths, FollowTheShortestWayAndCountTheTurns) {
  PoseGraph graph;
  for (int i = 0; i < 5; ++i) graph.poses.push_back(SE2());
  for (int i = 0; i < 4; ++i) {
    PoseGraphEdge edge;
    edge.from = i;
    edge.to = i + 1;
    edge.T_from_to = SE2(10.0, 0.0, std::numbers::pi / 2);
    graph.edges.push_back(edge);
  }
  const std::vector<GraphPath> open = graph_paths(graph, 4);
  EXPECT_DOUBLE_EQ(open[0].distance, 40.0);
  EXPECT_NEAR(open[0].turned, 2.0 * std::numbers::pi, 1e-12);
  EXPECT_DOUBLE_EQ(open[2].distance, 20.0);
  PoseGraphEdge loop;
  loop.from = 0;
  loop.to = 4;
  loop.T_from_to = SE2(0.5, 0.0, 0.0);
  graph.edges.push_back(loop);
  const std::vector<GraphPath> closed = graph_paths(graph, 4);
  EXPECT_DOUBLE_EQ(closed[0].distance, 0.5);
  EXPECT_DOUBLE_EQ(closed[0].turned, 0.0);
  EXPECT_DOUBLE_EQ(closed[1].distance, 10.5);
  EXPECT_DOUBLE_EQ(closed[2].distance, 20.0);  // either way round
  const std::vector<GraphPath> bounded = graph_paths(graph, 4, 5.0);
  EXPECT_TRUE(std::isinf(bounded[2].distance));
  EXPECT_EQ(nodes_within_graph_distance(graph, 4, 5.0), (std::vector<bool>{true, false, false, false, true}));
  // From several sources: the nearest one's path, as the least of the single-source searches.
  const std::vector<std::size_t> sources{1, 3};
  const std::vector<GraphPath> nearest = graph_paths(graph, sources);
  for (std::size_t n = 0; n < graph.size(); ++n) {
    EXPECT_DOUBLE_EQ(nearest[n].distance, std::min(graph_paths(graph, 1)[n].distance, graph_paths(graph, 3)[n].distance));
  }
  EXPECT_DOUBLE_EQ(nearest[4].distance, 10.0);
  EXPECT_EQ(nodes_within_graph_distance(graph, sources, 9.0), (std::vector<bool>{false, true, false, true, false}));
  EXPECT_EQ(nodes_within_graph_distance(graph, sources, 10.0), (std::vector<bool>{true, true, true, true, true}));
}

// A gap in the scans between nodes 1 and 2 of a straight line of 10 m steps: the step across it
// counts the drift the odometry may have gathered over the gap (gap_steps: the travel that the
// drift model turns into it), not the edge's own 10 m; unknown, it joins nothing.
TEST(GraphPaths, AStepAcrossAGapCountsTheOdometrysDriftOverIt) {
  PoseGraph graph;
  std::vector<Keyframe> keyframes(4);
  for (int i = 0; i < 4; ++i) {
    graph.poses.push_back(SE2(10.0 * i, 0.0, 0.0));
    keyframes[static_cast<std::size_t>(i)].node = static_cast<std::size_t>(i);
    if (i == 0) continue;
    PoseGraphEdge edge;
    edge.from = i - 1;
    edge.to = i;
    edge.T_from_to = SE2(10.0, 0.0, 0.0);
    graph.edges.push_back(edge);
  }
  const DriftModel model;
  keyframes[2].after_gap = true;
  keyframes[2].gap_drift_translation = 2.0;  // m
  keyframes[2].gap_drift_rotation = 0.5;     // rad
  const std::vector<std::optional<GraphPath>> steps = gap_steps(keyframes, graph.size(), model);
  ASSERT_TRUE(steps[2].has_value());
  EXPECT_FALSE(steps[1].has_value());
  const std::vector<GraphPath> paths = graph_paths(graph, 3, std::numeric_limits<double>::infinity(), &steps);
  EXPECT_DOUBLE_EQ(paths[2].distance, 10.0);
  const Drift across = drift_along(paths[1], model);  // 10 m of tracking and the gap
  EXPECT_NEAR(across.translation, 2.0 + 10.0 * model.translation_per_metre, 1e-9);
  EXPECT_NEAR(across.rotation, 0.5 + 10.0 * model.rotation_per_metre, 1e-9);
  EXPECT_GT(drift_along(paths[0], model).translation, across.translation);
  EXPECT_EQ(nodes_within_graph_distance(graph, 3, 25.0, &steps), (std::vector<bool>{false, false, true, true}));
  EXPECT_EQ(nodes_within_graph_distance(graph, 3, 25.0), (std::vector<bool>{false, true, true, true}));

  keyframes[2].gap_drift_translation = std::numeric_limits<double>::infinity();  // nothing told it
  const std::vector<std::optional<GraphPath>> unknown = gap_steps(keyframes, graph.size(), model);
  const std::vector<GraphPath> cut = graph_paths(graph, 3, std::numeric_limits<double>::infinity(), &unknown);
  EXPECT_TRUE(std::isinf(cut[1].distance));
  EXPECT_TRUE(std::isinf(drift_along(cut[0], model).translation));
  EXPECT_TRUE(std::isinf(drift_along(cut[0], model).rotation));
}

// The robot comes back to its start at the end of the log, 2 m off (the odometry carried it
// through the blind stretch and along the corridors the short-range laser cannot pin down). The
// log is cut just before the keyframe whose search closes the loop in a full run: then only the
// searches of finish() (from the keyframes the search interval skipped) can close it.
void expect_the_loop_at_the_end_of_the_log_closes(const GraphSlamConfig& config) {
  const SimulatedRun run = simulate_blinded_loop({});
  const std::size_t all = laser_messages(run).size();
  GraphSlamConfig open_config = config;
  open_config.loop_closure.enabled = false;
  const GraphSlam full = run_graph_slam(run, config, all);
  // The first loop edge of the full run: the scan of its (earliest) keyframe.
  std::optional<std::size_t> first_closing;
  for (const PoseGraphEdge& edge : full.graph().edges) {
    if (!is_loop_edge(edge)) continue;
    const std::size_t scan = full.keyframes()[static_cast<std::size_t>(edge.to)].scan;
    if (!first_closing || scan < *first_closing) first_closing = scan;
  }
  ASSERT_TRUE(first_closing.has_value()) << "the full run closes the loop";
  const GraphSlam open = run_graph_slam(run, open_config, *first_closing);
  const GraphSlam cut = run_graph_slam(run, config, *first_closing);
  EXPECT_GT(end_error(open, run), 1.0) << "the drift the loop closure must remove";
  EXPECT_GE(cut.stats().final_search_closures, 1u);
  EXPECT_EQ(cut.stats().loop_closures, cut.stats().final_search_closures) << "no closure before finish()";
  EXPECT_LT(end_error(cut, run), 0.3);
}

// With the defaults (the tracker's prior weighed by the motion noise, the sequential edges from the
// match, no odometry edges: docs/fusion_by_uncertainty.md) the drift is 1.4 m, 0.8 m of it across
// the corridor, and the refinement of the confirming keyframe's loop match cycles between sets of
// pairs 7 mm from the correlative pose. Before the point-to-line ICP took such a cycle for its end
// (PoseCycle) it ran out of iterations, the match counted as failed and the loop stayed open
// (1.34 m off).
TEST(GraphSlamLateLoops, ALoopThatClosesAtTheEndOfTheLogCloses) { expect_the_loop_at_the_end_of_the_log_closes({}); }

// The same with the tracker's fixed prior, as where the odometry is Hector's (map_job), with the
// fixed sequential covariance and odometry edges beside it (the defaults before 2026-12-03): the
// drift is 3 m, all of it along the corridor.
TEST(GraphSlamLateLoops, ALoopThatClosesAtTheEndOfTheLogClosesWithTheFixedTrackerPrior) {
  expect_the_loop_at_the_end_of_the_log_closes(test::graph_with_fixed_tracker_prior());
}

// Where the laser saw nothing, only the odometry held the path: the sequential edges there carry
// the odometry's noise (graph_slam.cpp, sequential_covariance) on top of the 2 mm floor, not the
// floor alone, so that a loop's correction goes into the blind stretch rather than everywhere
// alike. (This simulated odometry's noise is learnt at the model's lower bound, 0.2: its error is
// a scale and a heading bias, which the noise model does not describe; measured 4-5 mm a keyframe.)
TEST(GraphSlamLateLoops, TheBlindStretchsEdgesCarryTheOdometrysNoise) {
  const BlindedLoop loop;
  const SimulatedRun run = simulate_blinded_loop(loop);
  GraphSlamConfig config;
  config.loop_closure.enabled = false;
  const GraphSlam slam = run_graph_slam(run, config, laser_messages(run).size());
  const double floor_information = 1.0 / (config.sequential_sigma_translation * config.sequential_sigma_translation);
  std::size_t blind = 0;
  std::size_t seen = 0;
  for (const PoseGraphEdge& edge : slam.graph().edges) {
    if (is_loop_edge(edge)) continue;
    const double stamp = slam.keyframes()[static_cast<std::size_t>(edge.to)].stamp;
    const double information = edge.information(0, 0);
    if (stamp > loop.blind_from + 1.0 && stamp < loop.blind_until) {  // the first blind keyframe may still match
      ++blind;
      EXPECT_LT(information, floor_information / 3.0) << "blind keyframe at " << stamp << " s";
    } else if (stamp < loop.blind_from) {
      ++seen;
    }
  }
  EXPECT_GT(blind, 20u);
  EXPECT_GT(seen, 20u);
}

// A long loop: a blind stretch of 36 m on the far side of a 176 m lap with a heading bias of
// 0.01 rad/m leaves more than 12 m of drift at the start (the old maximum search radius) and a
// quarter of a radian (the odometry alone ends 28.7 m off). The robot's drift model says what such
// a robot can do (10.5 % of the distance, 0.15 %/m of heading in 3 sigmas); only the global
// search reaches that far. The tracker's drift at the keyframe that closes the loop is 15.8 m
// (fixed prior) to about 16.7 m (weighed prior) over about 184 m of graph path, 8.6-9.1 %: a model of
// 9 % held the one and refused the other at the edge (3.0 %/m per sigma refuses it, 3.1 %/m
// closes it), so the model holds it with a margin, not at its edge.
TEST(GraphSlamLateLoops, ALongDriftIsClosedByTheGlobalSearch) {
  const SimulatedRun run = simulate_blinded_loop(
      {.world_scale = 4.0, .duration = 175.0, .blind_from = 42.0, .blind_until = 72.0, .heading_bias = 0.01,
       .laser_range = 10.0});
  const std::size_t all = laser_messages(run).size();
  // The heading bias is the device that makes the drift: the tracker's calibration would take it
  // out (the open run's end 4.3 m off, not 12).
  GraphSlamConfig config = test::graph_without_calibration();
  config.loop_closure.drift.translation_per_metre = 0.035;
  config.loop_closure.drift.rotation_per_metre = 0.0005;
  GraphSlamConfig open_config = config;
  open_config.loop_closure.enabled = false;
  GraphSlamConfig local_config = config;
  local_config.loop_closure.large.global_search = false;
  const GraphSlam open = run_graph_slam(run, open_config, all);
  const GraphSlam local = run_graph_slam(run, local_config, all);
  const GraphSlam slam = run_graph_slam(run, config, all);
  EXPECT_GT(end_error(open, run), 12.0);
  EXPECT_GT(end_error(local, run), 12.0) << "the local search cannot reach it";
  EXPECT_GE(slam.stats().global_closures, 1u);
  EXPECT_GE(slam.stats().large_closures, 1u);
  EXPECT_LT(end_error(slam, run), 1.5);
  EXPECT_GT(slam.stats().global_search_seconds, 0.0);
}

}  // namespace
}  // namespace slam2d
