// SPDX-License-Identifier: BSD-3-Clause
// Micro benchmarks of the ICP family on real data: point-to-point ICP and its accelerated form
// (Besl & McKay 1992, registration/icp.*), trimmed ICP (Chetverikov 2002, trimmed_icp.*),
// point-to-plane (Low 2004, point_to_plane.*) and PL-ICP (Censi 2008, pl_icp.*, with its
// projective search and with the kd-tree), each on consecutive 180-beam Intel scans, single
// thread, the guess from odometry in the sensor frames:
//   T_guess = (odom_i T_robot_sensor)^-1 (odom_{i+1} T_robot_sensor).
// Each benchmark iteration is one match (the pairs cycle through the first scans of the log),
// so the time column is the time per match; `us_per_match` says the same as a counter, and
// `iterations` / `converged` are the means over the matches run. Issue 3's target: PL-ICP under
// 50 us per match.
//
//   build/<dir>/bin/slam2d_bench --benchmark_filter='Icp|PlIcp|PointToPlane'

#include <benchmark/benchmark.h>


#include "bench_data.hpp"
#include "slam2d/registration/icp.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "slam2d/registration/point_to_plane.hpp"
#include "slam2d/registration/trimmed_icp.hpp"

namespace {

using namespace slam2d;

/// One match per benchmark iteration on consecutive Intel scans (bench_data.hpp).
void run_intel(benchmark::State& state, const Matcher& match) { bench::run_consecutive_matches(state, match, "intel"); }

void BM_IcpIntel(benchmark::State& state) {
  run_intel(state, [](const PointCloud2& t, const PointCloud2& s, const SE2& g) { return match_icp(t, s, g); });
}
BENCHMARK(BM_IcpIntel)->Unit(benchmark::kMicrosecond);

void BM_IcpAcceleratedIntel(benchmark::State& state) {
  run_intel(state, [](const PointCloud2& t, const PointCloud2& s, const SE2& g) {
    return match_icp(t, s, g, {.accelerated = true});
  });
}
BENCHMARK(BM_IcpAcceleratedIntel)->Unit(benchmark::kMicrosecond);

void BM_TrimmedIcpIntel(benchmark::State& state) {
  run_intel(state, [](const PointCloud2& t, const PointCloud2& s, const SE2& g) { return match_trimmed_icp(t, s, g); });
}
BENCHMARK(BM_TrimmedIcpIntel)->Unit(benchmark::kMicrosecond);

void BM_PointToPlaneIntel(benchmark::State& state) {
  run_intel(state,
            [](const PointCloud2& t, const PointCloud2& s, const SE2& g) { return match_point_to_plane(t, s, g); });
}
BENCHMARK(BM_PointToPlaneIntel)->Unit(benchmark::kMicrosecond);

void BM_PlIcpIntel(benchmark::State& state) {
  const PlIcpConfig config{.search = static_cast<PlIcpSearch>(state.range(0))};
  run_intel(state, [&config](const PointCloud2& t, const PointCloud2& s, const SE2& g) {
    return match_pl_icp(t, s, g, config);
  });
}
BENCHMARK(BM_PlIcpIntel)
    ->ArgName("search")
    ->Arg(static_cast<int>(PlIcpSearch::kProjective))
    ->Arg(static_cast<int>(PlIcpSearch::kKdTree))
    ->Unit(benchmark::kMicrosecond);

}  // namespace
