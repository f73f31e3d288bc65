// SPDX-License-Identifier: BSD-3-Clause
// Rao-Blackwellized particle filter SLAM on several threads (RbpfConfig::threads): serial and
// parallel give the same trajectory, weights, statistics and maps, bit for bit, on a simulated run
// (also with resampling at almost every update, so that many tiles and path nodes are shared while
// the particles are updated in parallel) and on the first part of the ACES log.

#include <gtest/gtest.h>

#include <cstring>
#include <variant>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

struct ScanInput {
  LaserScan scan;
  SE2 odometry;
};

std::vector<ScanInput> inputs_of(const SimulatedRun& run) {
  std::vector<ScanInput> inputs;
  for (const LaserMessage* laser : laser_messages(run)) inputs.push_back({laser->scan, laser->odom_pose});
  return inputs;
}

RbpfSlam run_rbpf(const std::vector<ScanInput>& inputs, const RbpfConfig& config) {
  RbpfSlam slam(config);
  for (const ScanInput& input : inputs) slam.add_scan(input.scan, input.odometry);
  return slam;
}

// Number of cells (log-odds and last scan, compared as bytes) that differ between two grids, plus
// the tiles only one of them has.
std::size_t differing_cells(const OccupancyGrid& a, const OccupancyGrid& b) {
  using Tile = TiledGrid<OccupancyCell>::Tile;
  std::size_t differing = 0;
  a.cells().for_each_tile([&](CellIndex first, const Tile& tile) {
    const Tile* other = b.cells().find_tile(TiledGrid<OccupancyCell>::tile_of(first));
    if (other == nullptr) {
      differing += tile.cells.size();
      return;
    }
    for (std::size_t k = 0; k < tile.cells.size(); ++k) {
      differing += std::memcmp(&tile.cells[k], &other->cells[k], sizeof(OccupancyCell)) != 0 ? 1 : 0;
    }
  });
  if (a.cells().tile_count() != b.cells().tile_count()) ++differing;
  return differing;
}

// Everything the filter computes, compared exactly (doubles with ==, not a tolerance).
void expect_identical(const RbpfSlam& serial, const RbpfSlam& parallel) {
  EXPECT_EQ(serial.stats().updates, parallel.stats().updates);
  EXPECT_EQ(serial.stats().resamplings, parallel.stats().resamplings);
  EXPECT_EQ(serial.stats().fallbacks, parallel.stats().fallbacks);
  EXPECT_EQ(serial.stats().neff_min, parallel.stats().neff_min);
  EXPECT_EQ(serial.best_index(), parallel.best_index());
  ASSERT_EQ(serial.particles().size(), parallel.particles().size());
  for (std::size_t i = 0; i < serial.particles().size(); ++i) {
    const RbpfParticle& s = serial.particles()[i];
    const RbpfParticle& p = parallel.particles()[i];
    EXPECT_EQ(s.T_map_robot, p.T_map_robot) << "particle " << i;
    EXPECT_EQ(s.log_weight, p.log_weight) << "particle " << i;
    EXPECT_EQ(s.accumulated_log_weight, p.accumulated_log_weight) << "particle " << i;
    std::size_t nodes = 0;
    const RbpfPathNode* a = s.path.get();
    const RbpfPathNode* b = p.path.get();
    for (; a != nullptr && b != nullptr; a = a->parent.get(), b = b->parent.get(), ++nodes) {
      if (!(a->T_map_robot == b->T_map_robot) || a->update != b->update) break;
    }
    EXPECT_TRUE(a == nullptr && b == nullptr) << "particle " << i << ": paths differ after " << nodes << " nodes";
  }
  for (int level = 0; level < serial.best().map.levels(); ++level) {
    EXPECT_EQ(differing_cells(serial.best().map.level(level), parallel.best().map.level(level)), 0u) << "level " << level;
  }
  const Trajectory a = serial.trajectory();
  const Trajectory b = parallel.trajectory();
  ASSERT_EQ(a.size(), b.size());
  std::size_t differing_poses = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differing_poses += a[i].pose == b[i].pose ? 0 : 1;
  EXPECT_EQ(differing_poses, 0u);
}

TEST(RbpfParallel, SerialAndParallelGiveTheIdenticalTrajectoryAndWeights) {
  SimulationConfig sim;
  sim.duration = 60.0;
  sim.seed = 3;
  const std::vector<ScanInput> inputs = inputs_of(simulate(sim));
  RbpfConfig config{.particles = 8, .seed = 5, .threads = 1};
  const RbpfSlam serial = run_rbpf(inputs, config);
  ASSERT_GT(serial.stats().updates, 20u);
  ASSERT_GT(serial.stats().resamplings, 0u);  // shared tiles and path nodes at some updates
  for (const int threads : {2, 4}) {  // 4 > cores: more interleavings
    SCOPED_TRACE(threads);
    config.threads = threads;
    expect_identical(serial, run_rbpf(inputs, config));
  }
}

TEST(RbpfParallel, SerialAndParallelAgreeWhenResamplingAtEveryUpdate) {
  // Resampling whenever N_eff < N (every update with unequal weights): most particles start each
  // update as copies of another, so nearly every tile a scan writes is shared and is un-shared by
  // several threads at once.
  SimulationConfig sim;
  sim.duration = 40.0;
  sim.seed = 4;
  const std::vector<ScanInput> inputs = inputs_of(simulate(sim));
  RbpfConfig config{.particles = 8, .seed = 9, .threads = 1, .resample_threshold = 1.0};
  const RbpfSlam serial = run_rbpf(inputs, config);
  ASSERT_GT(serial.stats().resamplings, serial.stats().updates / 2);
  config.threads = 3;
  expect_identical(serial, run_rbpf(inputs, config));
}

TEST(RbpfParallel, AllHardwareThreadsIsTheDefault) {
  EXPECT_EQ(RbpfConfig{}.threads, 0);
  EXPECT_THROW(RbpfSlam({.threads = -1}), Error);
  EXPECT_THROW(RbpfSlam({.threads = 257}), Error);
  EXPECT_NO_THROW(RbpfSlam({.particles = 2, .threads = 256}));  // more threads than particles: capped
}

TEST(RbpfParallelRealData, AcesFirstScansSerialAndParallelAgree) {
  // The first 1200 scans of ACES (about 230 s of the log, 10 particles): a real map with real
  // resampling, a few seconds of CPU per run.
  SLAM2D_REQUIRE_REAL_DATA(data);
  std::vector<ScanInput> inputs;
  CarmenReader reader((data / "aces/aces.clf.gz").string());
  while (inputs.size() < 1200) {
    const auto message = reader.next();
    if (!message) break;
    if (const auto* laser = std::get_if<LaserMessage>(&*message)) inputs.push_back({laser->scan, laser->odom_pose});
  }
  ASSERT_EQ(inputs.size(), 1200u);
  RbpfConfig config{.particles = 10, .seed = 1, .threads = 1};
  const RbpfSlam serial = run_rbpf(inputs, config);
  ASSERT_GT(serial.stats().resamplings, 0u);
  config.threads = 2;
  expect_identical(serial, run_rbpf(inputs, config));
}

}  // namespace
}  // namespace slam2d
