// SPDX-License-Identifier: BSD-3-Clause
// Micro benchmarks of Hector SLAM (Kohlbrecher et al. 2011; src/slam2d/slam/hector): bilinear map
// sampling, one scan-to-pyramid match, and the whole loop per scan on the simulated office run.

#include <benchmark/benchmark.h>

#include <variant>
#include <vector>

#include "slam2d/grid/bilinear.hpp"
#include "slam2d/grid/map_pyramid.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "slam2d/registration/occupancy_gradient_match.hpp"
#include "slam2d/core/scan_preprocessing.hpp"

namespace {

using namespace slam2d;

const SimulatedRun& office_run() {
  static const SimulatedRun run = [] {
    SimulationConfig config;
    config.duration = 60.0;
    return simulate(config);
  }();
  return run;
}

std::vector<const LaserMessage*> lasers() {
  std::vector<const LaserMessage*> out;
  for (const SensorMessage& m : office_run().messages) {
    if (const auto* laser = std::get_if<LaserMessage>(&m)) out.push_back(laser);
  }
  return out;
}

MapPyramid office_map(int levels) {
  const auto scans = lasers();
  MapPyramid map({.levels = levels, .grid = {.resolution = 0.05, .probability_hit = 0.9, .max_range = 25.0}});
  for (std::size_t i = 0; i < scans.size(); i += 10) map.integrate_scan(scans[i]->scan, office_run().truth[i].pose);
  return map;
}

void BM_InterpolateOccupancy(benchmark::State& state) {
  const MapPyramid map = office_map(1);
  const auto points = usable_end_points(lasers()[100]->scan, 0.1, 25.0);
  const SE2 pose = office_run().truth[100].pose;
  std::vector<Eigen::Vector2d> world;
  for (const auto& p : points) world.push_back(pose * p);
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& p : world) sum += interpolate_occupancy(map.level(0), p).value;
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(world.size()));
}
BENCHMARK(BM_InterpolateOccupancy);

void BM_MatchScanToPyramid(benchmark::State& state) {
  const MapPyramid map = office_map(static_cast<int>(state.range(0)));
  const auto points = usable_end_points(lasers()[100]->scan, 0.1, 25.0);
  const SE2 guess = office_run().truth[100].pose * SE2(0.1, -0.05, 0.05);
  for (auto _ : state) benchmark::DoNotOptimize(match_scan_to_pyramid(map, points, guess));
}
BENCHMARK(BM_MatchScanToPyramid)->Arg(1)->Arg(3);

void BM_HectorSlamPerScan(benchmark::State& state) {
  const auto scans = lasers();
  HectorSlamConfig config;
  config.prior = state.range(0) != 0 ? MotionPrior::kOdometry : MotionPrior::kLastPose;
  for (auto _ : state) {
    HectorSlam slam(config);
    for (const LaserMessage* laser : scans) {
      HectorInputs inputs;
      inputs.T_odom_robot = laser->odom_pose;
      slam.add_scan(laser->scan, inputs);
    }
    benchmark::DoNotOptimize(slam.trajectory().back().pose);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(scans.size()));
}
BENCHMARK(BM_HectorSlamPerScan)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace
