// SPDX-License-Identifier: BSD-3-Clause
// Micro benchmarks of the occupancy grid (src/slam2d/grid): scan integration, copies, export.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/io/carmen.hpp"

namespace {

using slam2d::LaserScan;
using slam2d::OccupancyGrid;
using slam2d::SE2;

/// A 180 deg scan of `beams` beams taken at `pose` inside the rectangular room [-8, 8] x [-5, 5] m.
LaserScan room_scan(const SE2& pose, int beams) {
  LaserScan scan;
  scan.angle_min = -std::numbers::pi / 2;
  scan.angle_increment = std::numbers::pi / beams;
  scan.range_max = 80.0;
  for (int i = 0; i < beams; ++i) {
    const double a = pose.theta() + scan.angle(static_cast<std::size_t>(i));
    const double c = std::cos(a);
    const double s = std::sin(a);
    const double tx = c > 0 ? (8.0 - pose.x()) / c : c < 0 ? (-8.0 - pose.x()) / c : 1e9;
    const double ty = s > 0 ? (5.0 - pose.y()) / s : s < 0 ? (-5.0 - pose.y()) / s : 1e9;
    scan.ranges.push_back(std::min(tx, ty));
  }
  return scan;
}

/// Poses along an ellipse inside the room, and their scans.
struct Sequence {
  std::vector<SE2> poses;
  std::vector<LaserScan> scans;
};
Sequence room_sequence(int beams, int count) {
  Sequence sequence;
  for (int i = 0; i < count; ++i) {
    const double t = 2.0 * std::numbers::pi * i / count;
    const SE2 pose(5.0 * std::cos(t), 3.0 * std::sin(t), t + std::numbers::pi / 2);
    sequence.poses.push_back(pose);
    sequence.scans.push_back(room_scan(pose, beams));
  }
  return sequence;
}

void BM_IntegrateScan(benchmark::State& state) {
  const int beams = static_cast<int>(state.range(0));
  const Sequence sequence = room_sequence(beams, 100);
  OccupancyGrid grid(slam2d::OccupancyGridConfig{.resolution = 0.05});
  std::size_t i = 0;
  for (auto _ : state) {
    grid.integrate_scan(sequence.scans[i], sequence.poses[i]);
    i = (i + 1) % sequence.scans.size();
  }
  state.counters["beams"] = beams;
  state.SetItemsProcessed(state.iterations() * beams);
}
BENCHMARK(BM_IntegrateScan)->Arg(180)->Arg(360)->Unit(benchmark::kMicrosecond);

/// The SLAM-corrected Intel Research Lab log ($SLAM2D_DATA/intel/intel-corrected.log.gz, 910
/// scans of 180 beams), if present.
const std::vector<std::pair<LaserScan, SE2>>& intel_scans() {
  static const std::vector<std::pair<LaserScan, SE2>> scans = [] {
    std::vector<std::pair<LaserScan, SE2>> result;
    const char* data = std::getenv("SLAM2D_DATA");
    const std::string path = std::string(data != nullptr ? data : "") + "/intel/intel-corrected.log.gz";
    if (data == nullptr || !std::filesystem::exists(path)) return result;
    slam2d::CarmenReader reader(path);
    while (const auto message = reader.next()) {
      if (const auto* laser = std::get_if<slam2d::LaserMessage>(&*message)) {
        result.emplace_back(laser->scan, laser->laser_pose * laser->scan.T_robot_sensor.inverse());
      }
    }
    return result;
  }();
  return scans;
}

// Argument: grid.surface_hit_weight in tenths (0: the returns alone; 5: the RBPF's default, a
// grazing wall's cells between its returns filled at half a hit).
void BM_IntegrateIntelScan(benchmark::State& state) {
  const auto& scans = intel_scans();
  if (scans.empty()) {
    state.SkipWithError("set SLAM2D_DATA to the shared data folder");
    return;
  }
  const slam2d::OccupancyGridConfig config{.surface_hit_weight = static_cast<double>(state.range(0)) / 10.0};
  OccupancyGrid grid(config);
  std::size_t i = 0;
  for (auto _ : state) {
    grid.integrate_scan(scans[i].first, scans[i].second);
    if (++i == scans.size()) {  // start a fresh map each pass over the log
      state.PauseTiming();
      grid = OccupancyGrid(config);
      i = 0;
      state.ResumeTiming();
    }
  }
}
BENCHMARK(BM_IntegrateIntelScan)->Arg(0)->Arg(5)->Unit(benchmark::kMicrosecond);

void BM_CopyAndWrite(benchmark::State& state) {
  const Sequence sequence = room_sequence(180, 100);
  OccupancyGrid grid;
  for (std::size_t i = 0; i < sequence.scans.size(); ++i) grid.integrate_scan(sequence.scans[i], sequence.poses[i]);
  for (auto _ : state) {
    OccupancyGrid copy = grid;  // shares every tile
    copy.integrate_scan(sequence.scans[0], sequence.poses[0]);  // copies the tiles it writes
    benchmark::DoNotOptimize(copy.scan_count());
  }
}
BENCHMARK(BM_CopyAndWrite)->Unit(benchmark::kMicrosecond);

void BM_ToOccupancyMap(benchmark::State& state) {
  const Sequence sequence = room_sequence(180, 100);
  OccupancyGrid grid;
  for (std::size_t i = 0; i < sequence.scans.size(); ++i) grid.integrate_scan(sequence.scans[i], sequence.poses[i]);
  for (auto _ : state) benchmark::DoNotOptimize(grid.to_occupancy_map().cells.data());
  state.counters["cells"] = static_cast<double>(grid.to_occupancy_map().cells.size());
}
BENCHMARK(BM_ToOccupancyMap)->Unit(benchmark::kMicrosecond);

}  // namespace
