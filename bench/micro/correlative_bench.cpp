// SPDX-License-Identifier: BSD-3-Clause
// Micro benchmarks of correlative scan matching (Olson 2009, src/slam2d/registration/correlative.*):
// issue 3's case, a simulated 1080-beam, 270 deg scan pair in the office matched over a +-0.5 m,
// +-20 deg window at 1 cm / 0.25 deg, per search mode (the exhaustive search on that window takes
// seconds: it runs once, and on a +-0.1 m, +-5 deg window for a steady figure); the table build;
// and real Intel consecutive scans (180 beams) over +-0.3 m, +-15 deg, odometry as the guess.
//
//   build/<dir>/bin/slam2d_bench --benchmark_filter=Correlative

#include <benchmark/benchmark.h>

#include <cstddef>
#include <numbers>
#include <vector>

#include "bench_data.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/registration/correlative.hpp"
#include "slam2d/registration/correlative_grid.hpp"
#include "slam2d/sim/laser_model.hpp"
#include "slam2d/sim/ray_caster.hpp"
#include "slam2d/sim/world.hpp"

namespace {

using namespace slam2d;

constexpr double kDeg = std::numbers::pi / 180.0;

struct ScanPair {
  PointCloud2 target;
  PointCloud2 source;
  SE2 T_target_source;
};

/// As tests/registration/scan_pair_fixture.hpp's make_scan_pair (not linked into the benchmarks):
/// two scans of the office from T_world_target and T_world_target * T_target_source, sensor frames.
const ScanPair& office_pair_1080() {
  static const ScanPair pair = [] {
    const World world = make_world("office");
    const RayCaster caster(world);
    LaserModelConfig laser;
    laser.beams = 1080;
    laser.field_of_view = 270.0 * kDeg;
    laser.range_max = 30.0;
    laser.range_noise_sigma = 0.01;
    laser.dropout_probability = 0.0;
    Rng rng(1);
    const SE2 T_world_target(12.0, 6.0, 0.1);
    ScanPair p;
    p.T_target_source = SE2(0.15, -0.05, 0.05);
    p.target = to_point_cloud(simulate_scan(caster, T_world_target, 0.0, laser, rng), ScanFrame::kSensor).cloud;
    p.source = to_point_cloud(simulate_scan(caster, T_world_target * p.T_target_source, 0.1, laser, rng),
                              ScanFrame::kSensor).cloud;
    return p;
  }();
  return pair;
}

/// Issue 3's case: +-0.5 m, +-20 deg at 1 cm / 0.25 deg.
CorrelativeConfig issue_config(CorrelativeSearch search) {
  CorrelativeConfig config;
  config.resolution = 0.01;
  config.sigma = 0.02;
  config.window_x = 0.5;
  config.window_y = 0.5;
  config.window_theta = 20.0 * kDeg;
  config.angular_step = 0.25 * kDeg;
  config.search = search;
  return config;
}

const CorrelativeGrid& office_grid_1080() {
  static const CorrelativeGrid grid(office_pair_1080().target,
                                    correlative_grid_config(issue_config(CorrelativeSearch::kBranchAndBound)));
  return grid;
}

void run_match(benchmark::State& state, const CorrelativeConfig& config) {
  const auto& pair = office_pair_1080();
  const CorrelativeGrid& grid = office_grid_1080();
  MatchResult result;
  for (auto _ : state) {
    result = match_correlative(grid, pair.source, SE2(), config);
    benchmark::DoNotOptimize(result);
  }
  state.counters["poses_scored"] = result.iterations;
  state.counters["error_mm"] = 1e3 * (result.T_target_source.translation() - pair.T_target_source.translation()).norm();
  state.counters["points"] = static_cast<double>(pair.source.size());
}

void BM_Correlative1080_BranchAndBound(benchmark::State& state) {
  run_match(state, issue_config(CorrelativeSearch::kBranchAndBound));
}
BENCHMARK(BM_Correlative1080_BranchAndBound)->Unit(benchmark::kMillisecond);

void BM_Correlative1080_MultiResolution(benchmark::State& state) {
  CorrelativeConfig config = issue_config(CorrelativeSearch::kMultiResolution);
  config.low_resolution_steps = static_cast<int>(state.range(0));
  run_match(state, config);
}
BENCHMARK(BM_Correlative1080_MultiResolution)->Arg(8)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond);

/// The whole window, once: 101 x 101 x 161 poses.
void BM_Correlative1080_Exhaustive_FullWindow(benchmark::State& state) {
  run_match(state, issue_config(CorrelativeSearch::kExhaustive));
}
BENCHMARK(BM_Correlative1080_Exhaustive_FullWindow)->Iterations(1)->Unit(benchmark::kMillisecond);

/// A +-0.1 m, +-5 deg window (21 x 21 x 41 poses), to compare per pose.
void BM_Correlative1080_Exhaustive_SmallWindow(benchmark::State& state) {
  CorrelativeConfig config = issue_config(CorrelativeSearch::kExhaustive);
  config.window_x = config.window_y = 0.1;
  config.window_theta = 5.0 * kDeg;
  run_match(state, config);
}
BENCHMARK(BM_Correlative1080_Exhaustive_SmallWindow)->Unit(benchmark::kMillisecond);

/// The table of the 1080-beam target at 1 cm with the levels branch-and-bound needs.
void BM_Correlative1080_GridBuild(benchmark::State& state) {
  const auto& pair = office_pair_1080();
  const CorrelativeGridConfig config = correlative_grid_config(issue_config(CorrelativeSearch::kBranchAndBound));
  std::size_t bytes = 0;
  for (auto _ : state) {
    const CorrelativeGrid grid(pair.target, config);
    bytes = grid.memory_bytes();
    benchmark::DoNotOptimize(bytes);
  }
  state.counters["levels"] = config.levels;
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
}
BENCHMARK(BM_Correlative1080_GridBuild)->Unit(benchmark::kMillisecond);

/// Real consecutive Intel scans: table build and match per pair (the odometry use), in each mode.
void BM_CorrelativeIntel(benchmark::State& state) {
  const auto& scans = bench::logged_scans("intel", 401);
  if (scans.size() < 2) {
    state.SkipWithError("Intel data not found (set SLAM2D_DATA)");
    return;
  }
  std::vector<PointCloud2> clouds;
  for (const auto& s : scans) clouds.push_back(bench::sensor_cloud(s.scan));
  CorrelativeConfig config;
  config.window_x = config.window_y = 0.3;
  config.window_theta = 15.0 * kDeg;
  config.search = static_cast<CorrelativeSearch>(state.range(0));
  std::size_t i = 0;
  long long poses = 0;
  long long matches = 0;
  for (auto _ : state) {
    const SE2 guess = scans[i].odom_pose.between(scans[i + 1].odom_pose);
    const MatchResult result = match_correlative(clouds[i], clouds[i + 1], guess, config);
    benchmark::DoNotOptimize(result);
    poses += result.iterations;
    ++matches;
    i = (i + 1) % (scans.size() - 1);
  }
  state.counters["poses_scored"] = static_cast<double>(poses) / static_cast<double>(matches);
}
BENCHMARK(BM_CorrelativeIntel)
    ->ArgName("search")
    ->Arg(static_cast<int>(CorrelativeSearch::kBranchAndBound))
    ->Arg(static_cast<int>(CorrelativeSearch::kMultiResolution))
    ->Arg(static_cast<int>(CorrelativeSearch::kExhaustive))
    ->Unit(benchmark::kMillisecond);

}  // namespace
