// SPDX-License-Identifier: BSD-3-Clause
// The config field tables (core/config_fields.hpp) of the core, grid, optim, sim, eval,
// localization and slam configs: check_fields() holds each number to its range and names the
// field's path; a YAML dump (io/config_text.hpp) reads back (io/config_file.hpp) to the same
// values, for non-default configs and for the defaults of every struct with a table.

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry_guard.hpp"
#include "slam2d/core/odometry_repair.hpp"
#include "slam2d/eval/ate.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/eval/rpe.hpp"
#include "slam2d/grid/likelihood_field.hpp"
#include "slam2d/grid/map_pyramid.hpp"
#include "slam2d/grid/max_pool_pyramid.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/io/config_text.hpp"
#include "slam2d/io/input_limits.hpp"
#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/global_search.hpp"
#include "slam2d/localization/hybrid.hpp"
#include "slam2d/localization/localizer.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/localization/motion_model.hpp"
#include "slam2d/localization/sensor_model.hpp"
#include "slam2d/optim/robust_kernel.hpp"
#include "slam2d/optim/sparse_pose_adjustment.hpp"
#include "slam2d/sim/laser_model.hpp"
#include "slam2d/sim/odometry_model.hpp"
#include "slam2d/sim/route_follower.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/slam/fusion/discontinuity_smoothing.hpp"
#include "slam2d/slam/fusion/odometry_smoothing.hpp"
#include "slam2d/slam/fusion/trajectory_fusion.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "slam2d/slam/graph/keyframes.hpp"
#include "slam2d/slam/graph/loop_closure.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "slam2d/slam/rbpf/proposal.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"

namespace slam2d {
namespace {

// "path = value" per row: what a round trip must keep.
std::vector<std::string> values(const std::vector<FieldRow>& rows) {
  std::vector<std::string> out;
  for (const FieldRow& row : rows) out.push_back(row.path + " = " + row.value);
  return out;
}

template <typename Config>
std::vector<std::string> read_back(const Config& config) {
  const std::string text = config_yaml(field_rows(config));
  Config fresh{};
  read_config(ConfigNode::parse(text), fresh);
  return values(field_rows(fresh));
}

// check_fields accepts `config` as it is and rejects it with `set` applied, naming `path`.
template <typename Config, typename Set>
void expect_rejected(const Config& config, std::string_view name, Set set, const std::string& path) {
  EXPECT_NO_THROW(check_fields(config, name));
  Config bad = config;
  set(bad);
  try {
    check_fields(bad, name);
    ADD_FAILURE() << path << ": accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(path + " = "), std::string::npos) << error.what();
  }
}

TEST(ConfigFields, RangesRejectValuesJustOutsideEitherEnd) {
  const OccupancyGridConfig grid;
  expect_rejected(grid, "OccupancyGridConfig", [](auto& c) { c.probability_hit = 0.5; }, "OccupancyGridConfig.probability_hit");
  expect_rejected(grid, "OccupancyGridConfig", [](auto& c) { c.probability_hit = 1.0; }, "OccupancyGridConfig.probability_hit");
  expect_rejected(grid, "OccupancyGridConfig", [](auto& c) { c.resolution = 0.0; }, "OccupancyGridConfig.resolution");

  const LikelihoodFieldConfig field;
  expect_rejected(field, "LikelihoodFieldConfig", [](auto& c) { c.occupied_threshold = 0; },
                  "LikelihoodFieldConfig.occupied_threshold");
  expect_rejected(field, "LikelihoodFieldConfig", [](auto& c) { c.occupied_threshold = 101; },
                  "LikelihoodFieldConfig.occupied_threshold");
  EXPECT_NO_THROW(check_fields(LikelihoodFieldConfig{.occupied_threshold = 100}, "LikelihoodFieldConfig"));
  EXPECT_NO_THROW(check_fields(LikelihoodFieldConfig{.occupied_threshold = 1}, "LikelihoodFieldConfig"));

  const SparsePoseAdjustmentConfig spa;
  expect_rejected(spa, "SparsePoseAdjustmentConfig", [](auto& c) { c.lambda_down = 0.0; }, "SparsePoseAdjustmentConfig.lambda_down");
  expect_rejected(spa, "SparsePoseAdjustmentConfig", [](auto& c) { c.lambda_down = 1.0; }, "SparsePoseAdjustmentConfig.lambda_down");
  expect_rejected(spa, "SparsePoseAdjustmentConfig", [](auto& c) { c.loop_kernel.scale = 0.0; },
                  "SparsePoseAdjustmentConfig.loop_kernel.scale");

  const SimulationConfig simulation;
  expect_rejected(simulation, "SimulationConfig", [](auto& c) { c.duration = -1e-9; }, "SimulationConfig.duration");
  expect_rejected(simulation, "SimulationConfig", [](auto& c) { c.duration = 1e5 + 1e-6; }, "SimulationConfig.duration");
  expect_rejected(simulation, "SimulationConfig", [](auto& c) { c.laser.beams = 1; }, "SimulationConfig.laser.beams");
  expect_rejected(simulation, "SimulationConfig", [](auto& c) { c.odometry.scale_error = -1.0; },
                  "SimulationConfig.odometry.scale_error");

  const RpeConfig rpe;
  expect_rejected(rpe, "RpeConfig", [](auto& c) { c.delta = 0.0; }, "RpeConfig.delta");
  expect_rejected(rpe, "RpeConfig", [](auto& c) { c.stamp_tolerance = -1e-12; }, "RpeConfig.stamp_tolerance");

  const MclConfig mcl;
  expect_rejected(mcl, "MclConfig", [](auto& c) { c.likelihood_exponent = 0.0; }, "MclConfig.likelihood_exponent");
  expect_rejected(mcl, "MclConfig", [](auto& c) { c.likelihood_exponent = 1.0 + 1e-12; }, "MclConfig.likelihood_exponent");
  expect_rejected(mcl, "MclConfig", [](auto& c) { c.status.lost_after = 0; }, "MclConfig.status.lost_after");
  expect_rejected(mcl, "MclConfig", [](auto& c) { c.global.step_theta = 3.2; }, "MclConfig.global.step_theta");

  const RbpfConfig rbpf;
  expect_rejected(rbpf, "RbpfConfig", [](auto& c) { c.particles = 0; }, "RbpfConfig.particles");
  expect_rejected(rbpf, "RbpfConfig", [](auto& c) { c.particles = 10001; }, "RbpfConfig.particles");
  expect_rejected(rbpf, "RbpfConfig", [](auto& c) { c.threads = -1; }, "RbpfConfig.threads");
  expect_rejected(rbpf, "RbpfConfig", [](auto& c) { c.threads = 257; }, "RbpfConfig.threads");
  expect_rejected(rbpf, "RbpfConfig", [](auto& c) { c.proposal.sample_radius = 6; }, "RbpfConfig.proposal.sample_radius");

  const GraphSlamConfig graph;
  expect_rejected(graph, "GraphSlamConfig", [](auto& c) { c.tracking.map.levels = 17; }, "GraphSlamConfig.tracking.map.levels");
  expect_rejected(graph, "GraphSlamConfig", [](auto& c) { c.tracking.rotation_margin_without_odometry = 1.0; },
                  "GraphSlamConfig.tracking.rotation_margin_without_odometry");
  expect_rejected(graph, "GraphSlamConfig", [](auto& c) { c.loop_closure.large.min_score = 1.0 + 1e-12; },
                  "GraphSlamConfig.loop_closure.large.min_score");
  expect_rejected(graph, "GraphSlamConfig", [](auto& c) { c.loop_closure.min_inlier_fraction = -1e-12; },
                  "GraphSlamConfig.loop_closure.min_inlier_fraction");

  const OdometryGuardConfig guard;
  expect_rejected(guard, "OdometryGuardConfig", [](auto& c) { c.max_speed = std::numeric_limits<double>::quiet_NaN(); },
                  "OdometryGuardConfig.max_speed");
  expect_rejected(guard, "OdometryGuardConfig", [](auto& c) { c.gap = std::numeric_limits<double>::infinity(); },
                  "OdometryGuardConfig.gap");
}

TEST(ConfigFields, CrossFieldChecksStayInValidate) {
  EXPECT_NO_THROW(check_fields(HectorSlamConfig{.min_range = 5.0, .max_range = 5.0}, "HectorSlamConfig"));
  EXPECT_THROW(validate(HectorSlamConfig{.min_range = 5.0, .max_range = 5.0}), Error);
  EXPECT_THROW(validate(MclConfig{.min_particles = 10, .max_particles = 9}), Error);
  EXPECT_THROW(validate(MclConfig{.alpha_slow = 0.3, .alpha_fast = 0.3}), Error);
  EXPECT_THROW(validate(EkfConfig{.min_window_xy = 0.6, .max_window_xy = 0.5}), Error);
  EXPECT_THROW(validate(OdometryGuardConfig{.min_time_step = 0.3, .max_startup_time = 0.25}), Error);
  EXPECT_THROW(validate(BeamModelConfig{.z_hit = 0.0, .z_short = 0.0, .z_max = 0.0, .z_rand = 0.0}), Error);
  EXPECT_THROW(validate(LargeClosureConfig{.confirm_min_distance = 2.0, .confirm_max_distance = 1.0}), Error);
}

TEST(ConfigFields, NonDefaultConfigsReadBackFromTheirYamlDump) {
  HectorSlamConfig hector;
  hector.map.levels = 4;
  hector.map.grid.probability_hit = 0.8;
  hector.matcher.kernel = {.type = RobustKernelType::kTukey, .scale = 0.3};
  hector.prior = MotionPrior::kConstantVelocity;
  hector.prior_at_catch_ups = true;
  hector.max_range = 17.25;
  hector.odometry_guard.enabled = false;
  hector.odometry_guard.max_held_stall = 0.1;
  EXPECT_EQ(read_back(hector), values(field_rows(hector)));
  EXPECT_NE(values(field_rows(hector)), values(field_rows(HectorSlamConfig{})));

  MclConfig mcl;
  mcl.sensor = SensorModelKind::kBeam;
  mcl.beam.lambda_short = 0.3;
  mcl.max_particles = 12345;
  mcl.seed = 9007199254740993ULL;  // 2^53 + 1: not exact as a double
  mcl.global.max_poses = 7;
  mcl.kld_sampling = false;
  mcl.alpha_fast = 1.0;
  EXPECT_EQ(read_back(mcl), values(field_rows(mcl)));

  RbpfConfig rbpf;
  rbpf.particles = 7;
  rbpf.proposal.likelihood_stride = 3;
  rbpf.motion.stt = 1.0 / 3.0;  // not short in decimal: the dump must keep every digit
  rbpf.scan_matched_odometry = false;
  EXPECT_EQ(read_back(rbpf), values(field_rows(rbpf)));

  RpeConfig rpe{.window = RpeWindow::kTime, .delta = 2.5, .stamp_tolerance = 0.02};
  EXPECT_EQ(read_back(rpe), values(field_rows(rpe)));

  SimulationConfig simulation;
  simulation.laser.field_of_view = 2.0;
  simulation.odometry.heading_bias = -0.004;
  simulation.seed = 99;
  EXPECT_EQ(read_back(simulation), values(field_rows(simulation)));
}

// Every struct converted here, through one list: defaults pass check_fields() and validate()
// (where there is one), and their YAML dump reads back to the same rows.
template <typename Config>
class EveryConfigTable : public ::testing::Test {};

using Configs = ::testing::Types<
    ReverseOdometryRepairConfig, OdometryGuardConfig, LikelihoodFieldConfig, OccupancyGridConfig, MapPyramidConfig,
    MaxPoolPyramidConfig, RobustKernel, SparsePoseAdjustmentConfig, LaserModelConfig, OdometryModelConfig,
    RouteFollowerConfig, SimulationConfig, AteConfig, RpeConfig, RelationErrorConfig, GlobalSearchConfig,
    LocalizationStatusConfig, OdometryMotionConfig, BeamModelConfig, MarkovGridConfig, EkfConfig, MclConfig, HybridConfig,
    KeyframeConfig, DriftModel, LargeClosureConfig, LoopClosureConfig, GraphSlamConfig, HectorSlamConfig,
    RbpfMotionNoise, RbpfProposalConfig, RbpfConfig, DiscontinuitySmoothingConfig, FusionConfig, OdometrySmoothingConfig,
    InputLimits>;
TYPED_TEST_SUITE(EveryConfigTable, Configs);

TYPED_TEST(EveryConfigTable, DefaultsPassAndTheirYamlReadsBack) {
  const TypeParam defaults{};
  EXPECT_NO_THROW(check_fields(defaults, "defaults"));
  if constexpr (requires { validate(defaults); }) {
    EXPECT_NO_THROW(validate(defaults));
  }
  const std::vector<FieldRow> rows = field_rows(defaults);
  EXPECT_FALSE(rows.empty());
  EXPECT_EQ(read_back(defaults), values(rows));
}

}  // namespace
}  // namespace slam2d
