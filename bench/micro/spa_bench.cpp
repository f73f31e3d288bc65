// SPDX-License-Identifier: BSD-3-Clause
// Sparse pose adjustment (Konolige et al. 2010, src/slam2d/optim/sparse_pose_adjustment.*) on the
// public pose graphs of $SLAM2D_DATA/posegraphs (default ../shared/data), each from its own
// initial guess, one fresh optimisation per benchmark iteration; and the SLAM pattern on M3500: one
// optimiser called after every 100 nodes added (35 optimisations of a growing graph, re-analysed
// each time, warm-started from the previous poses).
//
//   build/<dir>/bin/slam2d_bench --benchmark_filter=Spa
//
// Counters: nodes, edges, initial_chi2, final_chi2, iterations (of the last run).
//
// BM_SpaGated: the same behind the pairwise consistency gate (optim/loop_consistency.hpp, `slam2d
// optimize`'s default), on the clean graph and on the graph with half its loop edges false at random
// (slam2d spoil --share 0.5 --seed 1), where plain least squares takes minutes (the fill-in).

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/optim/false_loop_closures.hpp"
#include "slam2d/optim/loop_consistency.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/optim/sparse_pose_adjustment.hpp"

namespace {

using namespace slam2d;

// The graph of $SLAM2D_DATA/posegraphs/<name>, read once; nullptr when absent.
const PoseGraph* pose_graph(const std::string& name) {
  static std::map<std::string, PoseGraph> cache;
  if (const auto it = cache.find(name); it != cache.end()) return &it->second;
  const char* data = std::getenv("SLAM2D_DATA");
  const std::filesystem::path path = std::filesystem::path(data ? data : "../shared/data") / "posegraphs" / name;
  if (!std::filesystem::exists(path)) return nullptr;
  return &cache.emplace(name, to_pose_graph(read_pose_graph(path.string()))).first->second;
}

void BM_Spa(benchmark::State& state, const std::string& name) {
  const PoseGraph* initial = pose_graph(name);
  if (initial == nullptr) {
    state.SkipWithError(("posegraphs/" + name + " not found (set SLAM2D_DATA)").c_str());
    return;
  }
  SparsePoseAdjustmentResult result;
  for (auto _ : state) {
    state.PauseTiming();
    PoseGraph graph = *initial;
    state.ResumeTiming();
    result = optimize_pose_graph(graph);
    benchmark::DoNotOptimize(graph.poses.data());
  }
  state.counters["nodes"] = static_cast<double>(initial->size());
  state.counters["edges"] = static_cast<double>(initial->edges.size());
  state.counters["initial_chi2"] = result.initial_chi2;
  state.counters["final_chi2"] = result.final_chi2;
  state.counters["iterations"] = result.iterations;
}

void BM_SpaGated(benchmark::State& state, const std::string& name, double false_share) {
  const PoseGraph* clean = pose_graph(name);
  if (clean == nullptr) {
    state.SkipWithError(("posegraphs/" + name + " not found (set SLAM2D_DATA)").c_str());
    return;
  }
  PoseGraph initial = *clean;
  for (PoseGraphEdge& edge : initial.edges) edge.robust = std::abs(edge.to - edge.from) > 1;
  if (false_share > 0.0) {
    initial = add_false_loop_closures(initial, FalseClosureConfig{.share = false_share}).graph;
    for (PoseGraphEdge& edge : initial.edges) edge.robust = std::abs(edge.to - edge.from) > 1;
  }
  GatedOptimization result;
  for (auto _ : state) {
    state.PauseTiming();
    PoseGraph graph = initial;
    state.ResumeTiming();
    result = optimize_gated(graph, SparsePoseAdjustmentConfig{}, InitialGuessChoice::kBetter, LoopConsistencyConfig{});
    benchmark::DoNotOptimize(graph.poses.data());
  }
  state.counters["loop_edges"] = static_cast<double>(result.loop_edges);
  state.counters["refused"] = static_cast<double>(result.refused);
  state.counters["final_chi2"] = result.optimization.result.final_chi2;
}

// M3500 as a SLAM run sees it: the first 100 k nodes and the edges among them, optimised by one
// SparsePoseAdjustment for k = 1..35; new nodes start from the last optimised pose composed with
// their odometry edge.
void BM_SpaIncrementalM3500(benchmark::State& state) {
  const PoseGraph* full = pose_graph("vertigo/manhattanOlson3500.g2o");
  if (full == nullptr) {
    state.SkipWithError("posegraphs/vertigo/manhattanOlson3500.g2o not found (set SLAM2D_DATA)");
    return;
  }
  int total_iterations = 0;
  double final_chi2 = 0.0;
  for (auto _ : state) {
    SparsePoseAdjustment spa;
    PoseGraph graph;
    total_iterations = 0;
    for (std::size_t nodes = 100; nodes <= full->size(); nodes += 100) {
      while (graph.size() < nodes) {
        const std::size_t k = graph.size();
        graph.poses.push_back(k == 0 ? full->poses[0] : graph.poses[k - 1] * full->poses[k - 1].between(full->poses[k]));
      }
      graph.edges.clear();
      for (const PoseGraphEdge& edge : full->edges) {
        if (static_cast<std::size_t>(std::max(edge.from, edge.to)) < nodes) graph.edges.push_back(edge);
      }
      const SparsePoseAdjustmentResult result = spa.optimize(graph);
      total_iterations += result.iterations;
      final_chi2 = result.final_chi2;
    }
  }
  state.counters["optimizations"] = static_cast<double>(full->size() / 100);
  state.counters["iterations"] = total_iterations;
  state.counters["final_chi2"] = final_chi2;
}

BENCHMARK_CAPTURE(BM_Spa, manhattanOlson3500, std::string("vertigo/manhattanOlson3500.g2o"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Spa, se_sync_intel, std::string("se-sync/intel.g2o"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Spa, vertigo_intel, std::string("vertigo/intel.g2o"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Spa, se_sync_manhattan_edges_only, std::string("se-sync/manhattan.g2o"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Spa, city10000, std::string("se-sync/city10000.g2o"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Spa, w10000_toro, std::string("hog-man/w10000.graph.gz"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Spa, ring, std::string("vertigo/ring.g2o"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Spa, ringCity, std::string("vertigo/ringCity.g2o"))->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SpaIncrementalM3500)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpaGated, manhattanOlson3500, std::string("vertigo/manhattanOlson3500.g2o"), 0.0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpaGated, se_sync_manhattan_edges_only, std::string("se-sync/manhattan.g2o"), 0.0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpaGated, city10000, std::string("se-sync/city10000.g2o"), 0.0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpaGated, city10000_half_false_random, std::string("se-sync/city10000.g2o"), 0.5)->Unit(benchmark::kMillisecond);

}  // namespace
