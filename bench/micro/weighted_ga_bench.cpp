// SPDX-License-Identifier: BSD-3-Clause
// Micro benchmarks of matchers as the CLI runs them, by preset file or registry name
// (matcher_registry.hpp):
// - the Boolean / soft-weighted ICP (six-step framework, Rusinkiewicz & Levoy 2001;
//   src/slam2d/registration/weighted_icp.*) and the GA + ICP hybrid (Martinez et al. 2006;
//   ga_icp.*): configs/boolean-icp.yaml, soft-icp.yaml, ga-icp.yaml;
// - the modular pipeline's presets (pipeline.*; configs/pipeline*.yaml), each next to the
//   dedicated matcher of the same paper at its defaults (icp, trimmed-icp, point-to-plane,
//   pl-icp), to show what the pipeline form costs.
// Two cases per matcher:
// - MatcherPresetIntel: real consecutive Intel scans (180 beams, the first 401), scan i + 1
//   (source) against scan i (target), odometry as the guess; one match per benchmark iteration,
//   so the time column is the time per match; counters: mean iterations, fraction converged,
//   mean inliers;
// - MatcherPresetOffice: a simulated 180-beam office pair with a known T_target_source
//   (0.15 m, -0.05 m, 0.05 rad) from the identity guess; counters: the estimate's error.
// Run from the repository root (the presets and, by default, ../shared/data):
//
//   SLAM2D_DATA=/work/shared/data build/<dir>/bin/slam2d_bench --benchmark_filter=MatcherPreset

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/methods/matcher_registry.hpp"
#include "slam2d/sim/laser_model.hpp"
#include "slam2d/sim/ray_caster.hpp"
#include "slam2d/sim/world.hpp"

namespace {

using namespace slam2d;

/// What is measured: preset files (configs/<name>.yaml) and registry names (defaults).
const std::vector<std::string> kMatchers = {
    "configs/boolean-icp.yaml",
    "configs/soft-icp.yaml",
    "configs/ga-icp.yaml",
    "icp",
    "configs/pipeline-besl1992.yaml",
    "trimmed-icp",
    "configs/pipeline-trimmed.yaml",
    "point-to-plane",
    "configs/pipeline-point-to-plane.yaml",
    "pl-icp",
    "configs/pipeline-pl-icp.yaml",
    "configs/pipeline.yaml",
};

/// The matcher of a preset path or registry name, or nullopt (and the state skipped).
std::optional<Matcher> load(benchmark::State& state, const std::string& argument) {
  if (argument.ends_with(".yaml") && !std::filesystem::exists(argument)) {
    state.SkipWithError((argument + " not found (run from the repository root)").c_str());
    return std::nullopt;
  }
  try {
    return matcher_from_argument(argument);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return std::nullopt;
  }
}

void intel(benchmark::State& state, const std::string& argument) {
  const auto& scans = bench::logged_scans("intel", 401);
  if (scans.size() < 2) {
    state.SkipWithError("Intel data not found (set SLAM2D_DATA)");
    return;
  }
  const std::optional<Matcher> matcher = load(state, argument);
  if (!matcher) return;
  std::vector<PointCloud2> clouds;
  for (const auto& s : scans) clouds.push_back(bench::sensor_cloud(s.scan));
  std::size_t i = 0;
  double matches = 0.0, iterations = 0.0, converged = 0.0, inliers = 0.0;
  for (auto _ : state) {
    const SE2 guess = scans[i].odom_pose.between(scans[i + 1].odom_pose);
    const MatchResult result = (*matcher)(clouds[i], clouds[i + 1], guess);
    benchmark::DoNotOptimize(result);
    matches += 1.0;
    iterations += result.iterations;
    converged += result.converged ? 1.0 : 0.0;
    inliers += static_cast<double>(result.inliers);
    i = (i + 1) % (scans.size() - 1);
  }
  state.counters["iterations"] = iterations / matches;
  state.counters["converged"] = converged / matches;
  state.counters["inliers"] = inliers / matches;
}

struct ScanPair {
  PointCloud2 target;
  PointCloud2 source;
  SE2 T_target_source;
};

/// As tests/registration/scan_pair_fixture.hpp's make_scan_pair (not linked into the benchmarks):
/// two 180-beam, 180 deg scans of the office, sensor frames.
const ScanPair& office_pair_180() {
  static const ScanPair pair = [] {
    const World world = make_world("office");
    const RayCaster caster(world);
    LaserModelConfig laser;
    laser.beams = 180;
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

void office(benchmark::State& state, const std::string& argument) {
  const std::optional<Matcher> matcher = load(state, argument);
  if (!matcher) return;
  const ScanPair& pair = office_pair_180();
  MatchResult result;
  for (auto _ : state) {
    result = (*matcher)(pair.target, pair.source, SE2());
    benchmark::DoNotOptimize(result);
  }
  const SE2& truth = pair.T_target_source;
  state.counters["error_mm"] = 1e3 * (result.T_target_source.translation() - truth.translation()).norm();
  state.counters["error_mrad"] = 1e3 * std::abs(angle_difference(result.T_target_source.theta(), truth.theta()));
  state.counters["iterations"] = result.iterations;
  state.counters["converged"] = result.converged ? 1.0 : 0.0;
}

/// "configs/pipeline-pl-icp.yaml" -> "pipeline-pl-icp"; a registry name stays as it is.
std::string label(const std::string& argument) {
  return argument.ends_with(".yaml") ? std::filesystem::path(argument).stem().string() : argument;
}

[[maybe_unused]] const bool kRegistered = [] {
  for (const std::string& argument : kMatchers) {
    benchmark::RegisterBenchmark(("MatcherPresetIntel/" + label(argument)).c_str(), intel, argument)
        ->Unit(benchmark::kMicrosecond);
  }
  for (const std::string& argument : kMatchers) {
    benchmark::RegisterBenchmark(("MatcherPresetOffice/" + label(argument)).c_str(), office, argument)
        ->Unit(benchmark::kMicrosecond);
  }
  return true;
}();

}  // namespace
