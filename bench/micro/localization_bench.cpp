// SPDX-License-Identifier: BSD-3-Clause
// Localization micro benchmarks: one filter update (motion, sensor, resampling) of MCL with 5000
// particles and 60 beams per scan, of the EKF with its scan-to-map match, and of the Markov grid
// while tracking, on the simulated office (180-beam scans, the ground-truth map at 5 cm).
// Targets (issue 7): MCL < 2 ms per update on one core, EKF < 0.5 ms.

#include <benchmark/benchmark.h>

#include <vector>

#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/sim/world.hpp"

namespace slam2d {
namespace {

SimulatedRun simulate_office() {
  SimulationConfig config;
  config.duration = 120.0;
  config.seed = 5;
  return simulate(config);
}

struct OfficeData {
  SimulatedRun run;
  std::vector<const LaserMessage*> lasers;
  LocalizationMap map;
  OfficeData()
      : run(simulate_office()),
        lasers(laser_messages(run)),
        map(rasterize_world(make_world("office"), 0.05)) {}
};

const OfficeData& office() {
  static const OfficeData data;
  return data;
}

// Runs the localizer over the run again and again; one iteration = one scan (every scan is a
// filter update: the update thresholds are 0).
template <typename Filter>
void run_updates(benchmark::State& state, Filter& filter) {
  const OfficeData& data = office();
  std::size_t i = 0;
  const std::size_t before = filter.sensor_updates();
  for (auto _ : state) {
    const LaserMessage* laser = data.lasers[i];
    benchmark::DoNotOptimize(filter.update(laser->odom_pose, laser->scan));
    if (++i == data.lasers.size()) {
      state.PauseTiming();
      i = 0;
      filter.initialize(data.run.truth[0].pose, covariance_from_sigmas(0.1, 0.1, 0.05));
      state.ResumeTiming();
    }
  }
  state.counters["updates_per_iteration"] =
      static_cast<double>(filter.sensor_updates() - before) / static_cast<double>(state.iterations());
}

void BM_MclUpdate(benchmark::State& state) {
  const OfficeData& data = office();
  MclConfig config;
  config.max_beams = 60;
  config.min_particles = config.max_particles = static_cast<std::size_t>(state.range(0));
  config.kld_sampling = false;
  config.update_distance = 0.0;
  config.update_angle = 0.0;
  MonteCarloLocalization mcl(data.map, config);
  mcl.initialize(data.run.truth[0].pose, covariance_from_sigmas(0.1, 0.1, 0.05));
  run_updates(state, mcl);
}
BENCHMARK(BM_MclUpdate)->Arg(1000)->Arg(5000)->Unit(benchmark::kMicrosecond);

void BM_EkfUpdate(benchmark::State& state) {
  const OfficeData& data = office();
  EkfLocalization ekf(data.map);
  ekf.initialize(data.run.truth[0].pose, covariance_from_sigmas(0.1, 0.1, 0.05));
  run_updates(state, ekf);
}
BENCHMARK(BM_EkfUpdate)->Unit(benchmark::kMicrosecond);

void BM_MarkovTrackingUpdate(benchmark::State& state) {
  const OfficeData& data = office();
  MarkovGridConfig config;
  config.update_distance = 0.0;
  config.update_angle = 0.0;
  MarkovGridLocalization markov(data.map, config);
  markov.initialize(data.run.truth[0].pose, covariance_from_sigmas(0.1, 0.1, 0.05));
  run_updates(state, markov);
}
BENCHMARK(BM_MarkovTrackingUpdate)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace slam2d
