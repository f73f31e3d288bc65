// SPDX-License-Identifier: BSD-3-Clause
// Micro benchmarks of the distance transform (Felzenszwalb and Huttenlocher 2012), the likelihood
// field (Thrun et al. 2005, Table 6.3) and the max-pooled pyramid (Cartographer's
// PrecomputationGrid2D): src/slam2d/grid/{distance_transform,likelihood_field,max_pool_pyramid}.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "slam2d/core/rng.hpp"
#include "slam2d/grid/distance_transform.hpp"
#include "slam2d/grid/likelihood_field.hpp"
#include "slam2d/grid/max_pool_pyramid.hpp"
#include "slam2d/sim/laser_model.hpp"
#include "slam2d/sim/ray_caster.hpp"
#include "slam2d/sim/world.hpp"

namespace {

using slam2d::LikelihoodField;
using slam2d::Rng;

/// A side x side grid with about `density` of its cells as sites.
std::vector<std::uint8_t> random_sites(int side, double density) {
  Rng rng(1);
  std::vector<std::uint8_t> sites(static_cast<std::size_t>(side) * side);
  for (auto& site : sites) site = rng.bernoulli(density) ? 1 : 0;
  return sites;
}

void BM_DistanceTransform(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  const bool nearest = state.range(1) != 0;
  const std::vector<std::uint8_t> sites = random_sites(side, 0.01);
  for (auto _ : state) {
    const slam2d::SquaredDistanceField field = slam2d::squared_distance_transform_of_sites(side, side, sites, nearest);
    benchmark::DoNotOptimize(field.squared_distances.data());
  }
  state.SetItemsProcessed(state.iterations() * side * side);
  state.counters["cells"] = static_cast<double>(side) * side;
}
BENCHMARK(BM_DistanceTransform)->Args({1000, 0})->Args({1000, 1})->Args({250, 0})->Unit(benchmark::kMillisecond);

const slam2d::OccupancyMap& office_map() {
  static const slam2d::OccupancyMap map = slam2d::rasterize_world(slam2d::make_world("office"), 0.05);
  return map;
}

const LikelihoodField& office_field() {
  static const LikelihoodField field(office_map());
  return field;
}

/// Points spread over the office floor (30 m x 20 m) and a little beyond.
std::vector<Eigen::Vector2d> query_points() {
  Rng rng(2);
  std::vector<Eigen::Vector2d> points(4096);
  for (auto& point : points) point = {rng.uniform(-1.0, 31.0), rng.uniform(-1.0, 21.0)};
  return points;
}

void BM_LikelihoodFieldBuild(benchmark::State& state) {
  for (auto _ : state) {
    const LikelihoodField field(office_map());
    benchmark::DoNotOptimize(field.width());
  }
  state.counters["samples"] = static_cast<double>(office_field().width()) * office_field().height();
}
BENCHMARK(BM_LikelihoodFieldBuild)->Unit(benchmark::kMillisecond);

void BM_LikelihoodFieldDistance(benchmark::State& state) {
  const LikelihoodField& field = office_field();
  const std::vector<Eigen::Vector2d> points = query_points();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(field.distance(points[i]));
    i = (i + 1) & (points.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LikelihoodFieldDistance);

void BM_LikelihoodFieldDistanceAndGradient(benchmark::State& state) {
  const LikelihoodField& field = office_field();
  const std::vector<Eigen::Vector2d> points = query_points();
  std::size_t i = 0;
  Eigen::Vector2d gradient;
  for (auto _ : state) {
    benchmark::DoNotOptimize(field.distance(points[i], &gradient));
    benchmark::DoNotOptimize(gradient.data());
    i = (i + 1) & (points.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LikelihoodFieldDistanceAndGradient);

/// The end points of a simulated scan in the office (map frame), queried in beam order.
void BM_LikelihoodFieldDistanceAlongScan(benchmark::State& state) {
  const LikelihoodField& field = office_field();
  const slam2d::RayCaster caster(slam2d::make_world("office"));
  Rng rng(3);
  const slam2d::SE2 pose(4.0, 6.0, 0.0);
  const slam2d::PointCloud2 points = slam2d::transform(
      slam2d::to_point_cloud(slam2d::simulate_scan(caster, pose, 0.0, slam2d::LaserModelConfig(), rng)).cloud, pose);
  for (auto _ : state) {
    double sum = 0.0;
    for (const Eigen::Vector2d& point : points.points) sum += field.distance(point);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long long>(points.size()));
}
BENCHMARK(BM_LikelihoodFieldDistanceAlongScan)->Unit(benchmark::kMicrosecond);

void BM_ScanLogLikelihood(benchmark::State& state) {
  const LikelihoodField& field = office_field();
  const slam2d::RayCaster caster(slam2d::make_world("office"));
  Rng rng(3);
  const slam2d::SE2 pose(4.0, 6.0, 0.0);
  const slam2d::PointCloud2 points =
      slam2d::to_point_cloud(slam2d::simulate_scan(caster, pose, 0.0, slam2d::LaserModelConfig(), rng)).cloud;
  for (auto _ : state) benchmark::DoNotOptimize(field.scan_log_likelihood(points, pose));
  state.SetItemsProcessed(state.iterations() * static_cast<long long>(points.size()));
  state.counters["points"] = static_cast<double>(points.size());
}
BENCHMARK(BM_ScanLogLikelihood)->Unit(benchmark::kMicrosecond);

void BM_MaxPoolPyramidBuild(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  const int levels = static_cast<int>(state.range(1));
  Rng rng(4);
  std::vector<float> scores(static_cast<std::size_t>(side) * side);
  for (float& score : scores) score = static_cast<float>(rng.uniform());
  for (auto _ : state) {
    const slam2d::MaxPoolPyramid pyramid(side, side, scores, {.levels = levels});
    benchmark::DoNotOptimize(pyramid.at(levels - 1, 0, 0));
  }
  state.SetItemsProcessed(state.iterations() * side * side * levels);
}
BENCHMARK(BM_MaxPoolPyramidBuild)->Args({1000, 7})->Args({500, 7})->Unit(benchmark::kMillisecond);

}  // namespace
