// SPDX-License-Identifier: BSD-3-Clause
// Micro benchmarks of Lu & Milios 1997 (registration/idc.*, registration/tangent_search.*):
// IMRP, IDC and the tangent-based rotation search on consecutive 180-beam Intel scans, single
// thread, the guess from odometry in the sensor frames:
//   T_guess = (odom_i T_robot_sensor)^-1 (odom_{i+1} T_robot_sensor).
// Each benchmark iteration is one match (the pairs cycle through the first 1000 scans of the
// log), so the time column is the time per match; `us_per_match` says the same as a counter,
// and `iterations` / `converged` are the means over the matches run.
//
//   build/<dir>/bin/slam2d_bench --benchmark_filter='Imrp|Idc|TangentSearch'

#include <benchmark/benchmark.h>


#include "bench_data.hpp"
#include "slam2d/registration/idc.hpp"
#include "slam2d/registration/tangent_search.hpp"

namespace {

using namespace slam2d;

/// One match per benchmark iteration on consecutive Intel scans (bench_data.hpp).
void run_intel(benchmark::State& state, const Matcher& match) { bench::run_consecutive_matches(state, match, "intel"); }

void BM_ImrpIntel(benchmark::State& state) {
  run_intel(state, [](const PointCloud2& t, const PointCloud2& s, const SE2& g) { return match_imrp(t, s, g); });
}
BENCHMARK(BM_ImrpIntel)->Unit(benchmark::kMicrosecond);

void BM_IdcIntel(benchmark::State& state) {
  run_intel(state, [](const PointCloud2& t, const PointCloud2& s, const SE2& g) { return match_idc(t, s, g); });
}
BENCHMARK(BM_IdcIntel)->Unit(benchmark::kMicrosecond);

void BM_TangentSearchIntel(benchmark::State& state) {
  run_intel(state,
            [](const PointCloud2& t, const PointCloud2& s, const SE2& g) { return match_tangent_search(t, s, g); });
}
BENCHMARK(BM_TangentSearchIntel)->Unit(benchmark::kMicrosecond);

}  // namespace
