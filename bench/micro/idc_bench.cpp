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

#include <cstddef>
#include <functional>
#include <vector>

#include "bench_data.hpp"
#include "slam2d/registration/idc.hpp"
#include "slam2d/registration/tangent_search.hpp"

namespace {

using namespace slam2d;

constexpr std::size_t kScans = 1001;

struct IntelPairs {
  std::vector<PointCloud2> clouds;
  std::vector<SE2> guesses;  // guesses[i]: T_sensor_i_sensor_{i+1}
};

const IntelPairs& intel_pairs() {
  static const IntelPairs pairs = [] {
    IntelPairs out;
    const auto& scans = bench::logged_scans("intel", kScans);
    for (const auto& s : scans) out.clouds.push_back(bench::sensor_cloud(s.scan));
    for (std::size_t i = 0; i + 1 < scans.size(); ++i) {
      const SE2 T_odom_sensor_i = scans[i].odom_pose * scans[i].scan.T_robot_sensor;
      const SE2 T_odom_sensor_j = scans[i + 1].odom_pose * scans[i + 1].scan.T_robot_sensor;
      out.guesses.push_back(T_odom_sensor_i.inverse() * T_odom_sensor_j);
    }
    return out;
  }();
  return pairs;
}

using BoundMatcher = std::function<MatchResult(const PointCloud2&, const PointCloud2&, const SE2&)>;

void run_intel(benchmark::State& state, const BoundMatcher& match) {
  const IntelPairs& pairs = intel_pairs();
  if (pairs.guesses.empty()) {
    state.SkipWithError("Intel data not found (set SLAM2D_DATA)");
    return;
  }
  std::size_t i = 0;
  double matches = 0.0;
  double iterations = 0.0;
  double converged = 0.0;
  for (auto _ : state) {
    const MatchResult result = match(pairs.clouds[i], pairs.clouds[i + 1], pairs.guesses[i]);
    benchmark::DoNotOptimize(result);
    matches += 1.0;
    iterations += result.iterations;
    converged += result.converged ? 1.0 : 0.0;
    i = (i + 1) % pairs.guesses.size();
  }
  state.counters["us_per_match"] =
      benchmark::Counter(matches * 1e-6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["iterations"] = iterations / matches;
  state.counters["converged"] = converged / matches;
}

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
