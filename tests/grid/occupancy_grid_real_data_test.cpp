// SPDX-License-Identifier: BSD-3-Clause
// The occupancy grid on real data: the SLAM-corrected Intel Research Lab log (shared/data,
// intel/intel-corrected.log.gz, 910 scans of 180 beams, poses corrected by a particle filter).

#include <gtest/gtest.h>

#include <ctime>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/grid/render.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/map_io.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

struct PosedScan {
  LaserScan scan;
  SE2 T_map_robot;
};

std::vector<PosedScan> read_corrected_log(const std::filesystem::path& path) {
  std::vector<PosedScan> scans;
  CarmenReader reader(path.string());
  while (const std::optional<SensorMessage> message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || !laser->has_poses) continue;
    // The FLASER "x y theta" triple is the laser's pose: T_map_robot = T_map_laser * T_robot_laser^-1.
    scans.push_back({laser->scan, laser->laser_pose * laser->scan.T_robot_sensor.inverse()});
  }
  return scans;
}

/// Fraction of the valid end points of `scans` that fall in cells the grid believes occupied.
double endpoint_consistency(const OccupancyGrid& grid, const std::vector<PosedScan>& scans) {
  std::size_t inside = 0;
  std::size_t total = 0;
  for (const PosedScan& s : scans) {
    const SE2 T_map_sensor = s.T_map_robot * s.scan.T_robot_sensor;
    for (const Point2& p : to_point_cloud(s.scan, ScanFrame::kSensor).cloud.points) {
      if (p.norm() >= 30.0) continue;
      ++total;
      inside += grid.probability(T_map_sensor * p) > 0.5 ? 1 : 0;
    }
  }
  return total == 0 ? 0.0 : static_cast<double>(inside) / static_cast<double>(total);
}

TEST(OccupancyGridRealData, IntelCorrectedLogBuildsAConsistentMap) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<PosedScan> scans = read_corrected_log(data / "intel" / "intel-corrected.log.gz");
  ASSERT_EQ(scans.size(), 910u);

  OccupancyGrid grid;  // 5 cm
  const std::clock_t start = std::clock();  // processor time: robust to a busy machine
  for (const PosedScan& s : scans) grid.integrate_scan(s.scan, s.T_map_robot);
  const double seconds = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  const OccupancyMap map = grid.to_occupancy_map();
  const double consistency = endpoint_consistency(grid, scans);

  // A grid built from poses with 10 cm / 2 deg of noise explains its own end points less well.
  OccupancyGrid noisy;
  std::mt19937 rng(5);
  std::normal_distribution<double> metres(0.0, 0.1);
  std::normal_distribution<double> radians(0.0, 0.035);
  std::vector<PosedScan> perturbed = scans;
  for (PosedScan& s : perturbed) s.T_map_robot = s.T_map_robot * SE2(metres(rng), metres(rng), radians(rng));
  for (const PosedScan& s : perturbed) noisy.integrate_scan(s.scan, s.T_map_robot);
  const double noisy_consistency = endpoint_consistency(noisy, perturbed);

  std::printf("[ intel-corrected ] %zu scans, %.1f us (CPU) per scan, map %d x %d cells (%.1f x %.1f m), %.1f MB, "
              "end points in occupied cells %.3f (noisy poses %.3f)\n",
              scans.size(), 1e6 * seconds / static_cast<double>(scans.size()), map.width, map.height,
              map.width * map.resolution, map.height * map.resolution, grid.memory_bytes() / 1e6, consistency,
              noisy_consistency);
  // The Intel lab is about 30 m x 30 m: its walls (occupied cells) span about that much, while
  // no-return beams clear free space up to max_clear_range around the robot's path.
  CellBox walls;
  for (int iy = 0; iy < map.height; ++iy) {
    for (int ix = 0; ix < map.width; ++ix) {
      if (map.at(ix, iy) > 65) walls.extend(CellIndex{ix, iy});
    }
  }
  std::printf("[ intel-corrected ] occupied cells span %.1f x %.1f m\n", walls.width() * map.resolution,
              walls.height() * map.resolution);
  EXPECT_GT(walls.width() * map.resolution, 25.0);
  EXPECT_LT(walls.width() * map.resolution, 50.0);
  EXPECT_GT(walls.height() * map.resolution, 25.0);
  EXPECT_LT(walls.height() * map.resolution, 50.0);
  EXPECT_LT(map.width * map.resolution, (walls.width() + 2) * map.resolution + 2 * grid.config().max_clear_range);
  EXPECT_LT(map.height * map.resolution, (walls.height() + 2) * map.resolution + 2 * grid.config().max_clear_range);
  EXPECT_GT(consistency, 0.7);  // measured 0.81
  EXPECT_GT(consistency, noisy_consistency + 0.3);  // measured 0.24

  // Files: the map written and read back as map_server trinary cells, and the rendered picture.
  test::TempDir dir;
  write_map(dir.file("intel.yaml"), map);
  const OccupancyMap back = read_map(dir.file("intel.yaml"));
  ASSERT_EQ(back.cells.size(), map.cells.size());
  for (std::size_t i = 0; i < map.cells.size(); ++i) {
    const int v = map.cells[i];
    const int expected = v < 0 ? -1 : v > 65 ? 100 : v < 19.6 ? 0 : -1;
    ASSERT_EQ(back.cells[i], expected) << i;
  }
  std::vector<SE2> trajectory;
  for (const PosedScan& s : scans) trajectory.push_back(s.T_map_robot);
  const RgbImage picture = render_map(map, trajectory, RenderOptions{.scale = 1});
  write_png(dir.file("intel.png"), picture);
  EXPECT_EQ(read_png_rgb(dir.file("intel.png")), picture);
}

}  // namespace
}  // namespace slam2d
