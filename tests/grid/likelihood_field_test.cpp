// SPDX-License-Identifier: BSD-3-Clause
// Likelihood field (Thrun et al. 2005, Table 6.3): distances against brute force, the gradient
// against finite differences and the true direction, hand-computed likelihoods, and the scan
// log-likelihood peaking at the true pose of a simulated scan.

#include "slam2d/grid/likelihood_field.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <utility>
#include <variant>
#include <numbers>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/sim/laser_model.hpp"
#include "slam2d/sim/ray_caster.hpp"
#include "slam2d/sim/world.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

constexpr double kFloat = 2e-6;  // m: distances are stored as float

/// A w x h map with cells drawn from {-1, 0, 30, 64, 65, 100} (about `obstacles` of them >= 65).
OccupancyMap random_map(int width, int height, double resolution, const SE2& origin, double obstacles, Rng& rng) {
  OccupancyMap map;
  map.resolution = resolution;
  map.origin = origin;
  map.width = width;
  map.height = height;
  const std::int8_t low[] = {-1, 0, 30, 64};
  for (int i = 0; i < width * height; ++i) {
    const bool occupied = rng.bernoulli(obstacles);
    map.cells.push_back(occupied ? (rng.bernoulli(0.5) ? 65 : 100) : low[rng.uniform_index(4)]);
  }
  return map;
}

/// min(max_distance, distance from `point` to the nearest obstacle cell centre), by brute force.
double brute_force_distance(const OccupancyMap& map, const Eigen::Vector2d& point, double max_distance) {
  double best = max_distance;
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if (map.at(x, y) >= 65) best = std::min(best, (map.cell_center(x, y) - point).norm());
    }
  }
  return best;
}

/// A point uniformly drawn in the map's box grown by `grow` m on each side.
Eigen::Vector2d random_point(const OccupancyMap& map, double grow, Rng& rng) {
  const Eigen::Vector2d local(rng.uniform(-grow, map.width * map.resolution + grow),
                              rng.uniform(-grow, map.height * map.resolution + grow));
  return map.origin.act(local);
}

OccupancyMap single_obstacle_map(int width, int height, double resolution, int ox, int oy) {
  OccupancyMap map;
  map.resolution = resolution;
  map.width = width;
  map.height = height;
  map.cells.assign(static_cast<std::size_t>(width) * height, OccupancyMap::kFree);
  map.at(ox, oy) = OccupancyMap::kOccupied;
  return map;
}

TEST(LikelihoodField, DistanceAtCellCentresMatchesBruteForce) {
  Rng rng(1);
  const OccupancyMap map = random_map(40, 30, 0.1, SE2(1.0, -2.0, 0.3), 0.02, rng);
  const LikelihoodField field(map, {.max_distance = 0.8});
  EXPECT_EQ(field.margin_cells(), 9);
  EXPECT_EQ(field.width(), 40 + 18);
  for (int y = -3; y < map.height + 3; ++y) {
    for (int x = -3; x < map.width + 3; ++x) {
      const Eigen::Vector2d centre = map.cell_center(x, y);
      ASSERT_NEAR(field.distance(centre), brute_force_distance(map, centre, 0.8), kFloat) << x << ", " << y;
    }
  }
}

TEST(LikelihoodField, DistanceAtRandomPointsIsWithinTheInterpolationBound) {
  // Bilinear interpolation of a 1-Lipschitz function errs by at most the bilinear-weighted mean
  // distance to the four samples, which is largest (r / sqrt(2)) at a cell's centre.
  Rng rng(2);
  const OccupancyMap map = random_map(50, 40, 0.05, SE2(-3.0, 4.0, -1.2), 0.01, rng);
  const LikelihoodField field(map, {.max_distance = 0.6});
  double worst = 0.0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector2d point = random_point(map, 1.0, rng);
    const double error = std::abs(field.distance(point) - brute_force_distance(map, point, 0.6));
    worst = std::max(worst, error);
  }
  EXPECT_LE(worst, 0.05 / std::sqrt(2.0) + kFloat);
  EXPECT_GT(worst, 0.0);  // the bound is not vacuous: points off the centres do differ
}

TEST(LikelihoodField, OutsideTheFieldIsMaxDistanceAndNonFiniteIsNaN) {
  const LikelihoodField field(single_obstacle_map(20, 20, 0.1, 10, 10), {.max_distance = 0.5});
  Eigen::Vector2d gradient(1.0, 1.0);
  EXPECT_EQ(field.distance({-50.0, 3.0}, &gradient), 0.5);
  EXPECT_EQ(gradient, Eigen::Vector2d::Zero());
  EXPECT_EQ(field.distance({1e300, -1e300}), 0.5);
  EXPECT_TRUE(std::isnan(field.distance({std::numeric_limits<double>::infinity(), 0.0})));
  EXPECT_TRUE(std::isnan(field.distance({std::numeric_limits<double>::quiet_NaN(), 1.0}, &gradient)));
  EXPECT_TRUE(std::isnan(gradient.x()));
  // Just inside the field's edge the samples are already capped: no step at the border, even for
  // a cap that float does not represent exactly.
  const double edge = -field.margin_cells() * 0.1;
  EXPECT_EQ(field.distance({edge + 0.051, 1.0}), 0.5);
  const LikelihoodField odd_cap(single_obstacle_map(20, 20, 0.1, 10, 10), {.max_distance = 0.3});
  const double odd_edge = -odd_cap.margin_cells() * 0.1;
  EXPECT_EQ(odd_cap.distance({odd_edge + 0.0501, 1.0}), odd_cap.distance({odd_edge - 0.0501, 1.0}));
  EXPECT_EQ(odd_cap.distance({odd_edge - 0.0501, 1.0}), static_cast<double>(0.3f));
  EXPECT_NEAR(field.distance({1.05, 1.05}), 0.0, kFloat);  // the obstacle's centre
}

TEST(LikelihoodField, EmptyMapsGiveMaxDistanceEverywhere) {
  OccupancyMap free_map = single_obstacle_map(10, 10, 0.1, 0, 0);
  free_map.at(0, 0) = 0;
  const LikelihoodField field(free_map);
  EXPECT_EQ(field.distance({0.5, 0.5}), 2.0);
  const LikelihoodField empty(OccupancyMap{});
  EXPECT_EQ(empty.width(), 0);
  EXPECT_EQ(empty.distance({0.0, 0.0}), 2.0);
  EXPECT_EQ(LikelihoodField(OccupancyGrid{}, CellBox{}).distance({1.0, 1.0}), 2.0);
}

TEST(LikelihoodField, GradientMatchesFiniteDifferencesInsideCells) {
  Rng rng(3);
  const OccupancyMap map = random_map(40, 40, 0.05, SE2(0.5, 0.25, 0.7), 0.01, rng);
  const LikelihoodField field(map, {.max_distance = 0.5});
  const double h = 1e-6;
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d point = random_point(map, 0.3, rng);
    // Stay clear of the cell edges of the sample lattice, where the derivative jumps.
    const Eigen::Vector2d u = field.origin().inverse().act(point) / 0.05 - Eigen::Vector2d(0.5, 0.5);
    const Eigen::Vector2d fraction = u - u.array().floor().matrix();
    if ((fraction.array() < 0.01).any() || (fraction.array() > 0.99).any()) continue;
    Eigen::Vector2d gradient;
    field.distance(point, &gradient);
    Eigen::Vector2d numeric;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d step = Eigen::Vector2d::Unit(k) * h;
      numeric[k] = (field.distance(point + step) - field.distance(point - step)) / (2 * h);
    }
    ASSERT_NEAR((gradient - numeric).norm(), 0.0, 1e-6) << point.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 1700);
}

TEST(LikelihoodField, GradientPointsAwayFromTheObstacleAwayFromRidges) {
  // One obstacle: the true distance is a cone, its gradient the unit vector away from the
  // obstacle (no ridge anywhere). The interpolated gradient follows it.
  const OccupancyMap map = single_obstacle_map(60, 60, 0.05, 30, 30);
  const LikelihoodField field(map, {.max_distance = 2.0});
  const Eigen::Vector2d obstacle = map.cell_center(30, 30);
  Rng rng(4);
  for (int i = 0; i < 500; ++i) {
    const double angle = rng.uniform(-std::numbers::pi, std::numbers::pi);
    const double radius = rng.uniform(0.5, 1.4);
    const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
    Eigen::Vector2d gradient;
    const double d = field.distance(obstacle + radius * direction, &gradient);
    EXPECT_NEAR(d, radius, 0.01);
    EXPECT_NEAR(gradient.norm(), 1.0, 0.06);
    EXPECT_GT(gradient.normalized().dot(direction), std::cos(0.06));
  }
}

TEST(LikelihoodField, LikelihoodsMatchHandComputedValues) {
  // Obstacle at the centre of cell (10, 10) = (1.05, 1.05); the centre of cell (13, 14) lies
  // 0.3 m, 0.4 m away: d = 0.5 m exactly.
  const LikelihoodFieldConfig config{.max_distance = 2.0, .sigma_hit = 0.2, .z_hit = 0.8, .z_rand = 0.2, .z_max = 10.0};
  const LikelihoodField field(single_obstacle_map(30, 30, 0.1, 10, 10), config);
  const Eigen::Vector2d point(1.35, 1.45);
  EXPECT_NEAR(field.distance(point), 0.5, kFloat);
  EXPECT_NEAR(field.likelihood(point), std::exp(-3.125), 1e-6);  // exp(-0.25 / 0.08)
  const double hit = 0.8 / (std::sqrt(2.0 * std::numbers::pi) * 0.2);  // 1.59577 1/m
  EXPECT_NEAR(field.beam_likelihood(point), hit * std::exp(-3.125) + 0.02, 1e-6);
  EXPECT_NEAR(field.likelihood({1.05, 1.05}), 1.0, 1e-6);
  EXPECT_NEAR(field.beam_likelihood({1.05, 1.05}), hit + 0.02, 1e-6);
  // Far away: only the random component (and the capped Gaussian, exp(-4 / 0.08) ~ 2e-22).
  EXPECT_NEAR(field.beam_likelihood({-40.0, 7.0}), 0.02, 1e-12);

  // A two-point scan from T_map_robot = (1.05, 1.45, -pi/2): robot-frame (0.4, 0) is on the
  // obstacle, (0, -0.3) is at map (0.75, 1.45), 0.3 and 0.4 m from the obstacle: d = 0.5 again.
  PointCloud2 points;
  points.points = {{0.4, 0.0}, {0.0, -0.3}};
  const SE2 T_map_robot(1.05, 1.45, -std::numbers::pi / 2);
  const double expected = std::log(hit + 0.02) + std::log(hit * std::exp(-3.125) + 0.02);
  EXPECT_NEAR(field.scan_log_likelihood(points, T_map_robot), expected, 1e-5);
  EXPECT_EQ(field.scan_log_likelihood(PointCloud2{}, T_map_robot), 0.0);
}

TEST(LikelihoodField, OccupancyGridRegionAgreesWithItsOccupancyMap) {
  const World world = make_world("office");
  const RayCaster caster(world);
  Rng rng(5);
  LaserModelConfig laser;
  laser.beams = 360;
  OccupancyGrid grid;
  for (const Eigen::Vector2d& waypoint : world.route) {
    const SE2 pose(waypoint, 0.3);
    grid.integrate_scan(simulate_scan(caster, pose, 0.0, laser, rng), pose);
  }
  const OccupancyMap map = grid.to_occupancy_map();
  const LikelihoodField from_grid(grid, grid.observed_box(), {.max_distance = 1.0});
  const LikelihoodField from_map(map, {.max_distance = 1.0});
  int obstacles = 0;
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector2d point = random_point(map, 0.5, rng);
    ASSERT_NEAR(from_grid.distance(point), from_map.distance(point), kFloat) << point.transpose();
    obstacles += from_map.distance(point) < 0.5 ? 1 : 0;
  }
  EXPECT_GT(obstacles, 500);  // the maps do have walls
}

TEST(LikelihoodField, ScanLogLikelihoodPeaksAtTheTruePose) {
  const World world = make_world("office");
  const LikelihoodField field(rasterize_world(world, 0.05), {.sigma_hit = 0.05});
  const RayCaster caster(world);
  Rng rng(6);
  const std::vector<SE2> truths{SE2(4.0, 6.0, 0.0), SE2(20.0, 8.0, 1.2), SE2(12.0, 2.0, -2.5), SE2(24.5, 10.0, 2.0)};
  for (const SE2& truth : truths) {
    const LaserScan scan = simulate_scan(caster, truth, 0.0, LaserModelConfig{}, rng);
    const PointCloud2 points = to_point_cloud(scan, ScanFrame::kRobot).cloud;
    ASSERT_GT(points.size(), 150u);
    const double at_truth = field.scan_log_likelihood(points, truth);
    double sum_of_logs = 0.0;  // Table 6.3 term by term (the field multiplies in chunks)
    for (const Point2& point : points.points) sum_of_logs += std::log(field.beam_likelihood(truth * point));
    EXPECT_NEAR(at_truth, sum_of_logs, 1e-9 * std::abs(sum_of_logs));
    for (double dx : {-0.2, -0.1, 0.0, 0.1, 0.2}) {
      for (double dy : {-0.2, -0.1, 0.0, 0.1, 0.2}) {
        for (double dtheta : {-0.05, 0.0, 0.05}) {
          if (dx == 0.0 && dy == 0.0 && dtheta == 0.0) continue;
          const SE2 moved = truth * SE2(dx, dy, dtheta);
          EXPECT_LT(field.scan_log_likelihood(points, moved), at_truth) << truth << " moved by " << dx << " "
                                                                        << dy << " " << dtheta;
        }
      }
    }
  }
}

TEST(LikelihoodFieldRealData, IntelCorrectedScansScoreBestAtTheirPoses) {
  // The SLAM-corrected Intel log (910 scans): a field of the map of the even scans scores each odd
  // scan (not in the map) at its corrected pose and at 8 poses moved by 0.1 m or 0.05 rad.
  SLAM2D_REQUIRE_REAL_DATA(data);
  std::vector<std::pair<LaserScan, SE2>> scans;  // T_map_robot = T_map_laser * T_robot_laser^-1
  CarmenReader reader((data / "intel" / "intel-corrected.log.gz").string());
  while (const std::optional<SensorMessage> message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser != nullptr && laser->has_poses) {
      scans.emplace_back(laser->scan, laser->laser_pose * laser->scan.T_robot_sensor.inverse());
    }
  }
  ASSERT_EQ(scans.size(), 910u);
  OccupancyGrid grid;
  for (std::size_t i = 0; i < scans.size(); i += 2) grid.integrate_scan(scans[i].first, scans[i].second);
  const LikelihoodField field(grid, grid.observed_box(), {.sigma_hit = 0.05});
  const std::vector<SE2> moves{SE2(0.1, 0, 0),  SE2(-0.1, 0, 0), SE2(0, 0.1, 0),    SE2(0, -0.1, 0),
                               SE2(0, 0, 0.05), SE2(0, 0, -0.05), SE2(0.1, 0.1, 0), SE2(-0.1, -0.1, 0)};
  int wins = 0;
  int trials = 0;
  for (std::size_t i = 1; i < scans.size(); i += 2) {
    const PointCloud2 points = to_point_cloud(scans[i].first, ScanFrame::kRobot).cloud;
    const double at_pose = field.scan_log_likelihood(points, scans[i].second);
    for (const SE2& move : moves) {
      wins += at_pose > field.scan_log_likelihood(points, scans[i].second * move) ? 1 : 0;
      ++trials;
    }
  }
  const double fraction = static_cast<double>(wins) / trials;
  std::printf("[ figures  ] intel-corrected: the corrected pose beats 0.1 m / 0.05 rad moves in %.4f of %d cases\n",
              fraction, trials);
  EXPECT_GT(fraction, 0.95);
}

TEST(LikelihoodField, RejectsBadInput) {
  const OccupancyMap map = single_obstacle_map(5, 5, 0.1, 2, 2);
  EXPECT_THROW(LikelihoodField(map, {.max_distance = 0.0}), Error);
  EXPECT_THROW(LikelihoodField(map, {.max_distance = std::numeric_limits<double>::quiet_NaN()}), Error);
  EXPECT_THROW(LikelihoodField(map, {.occupied_threshold = 0}), Error);
  EXPECT_THROW(LikelihoodField(map, {.occupied_threshold = 101}), Error);
  EXPECT_THROW(LikelihoodField(map, {.sigma_hit = -1.0}), Error);
  EXPECT_THROW(LikelihoodField(map, {.z_hit = -0.5}), Error);
  EXPECT_THROW(LikelihoodField(map, {.z_rand = 0.0}), Error);
  EXPECT_THROW(LikelihoodField(map, {.z_max = 0.0}), Error);
  EXPECT_THROW(LikelihoodField(map, {.z_rand = 1e-200, .z_max = 1e200}), Error);  // uniform density underflows
  EXPECT_THROW(LikelihoodField(map, {.max_distance = 1e6}), Error);  // too many samples
  OccupancyMap broken = map;
  broken.cells.pop_back();
  EXPECT_THROW(LikelihoodField{broken}, Error);
  broken = map;
  broken.resolution = 0.0;
  EXPECT_THROW(LikelihoodField{broken}, Error);
  broken = map;
  broken.origin = SE2(std::numeric_limits<double>::infinity(), 0.0, 0.0);
  EXPECT_THROW(LikelihoodField{broken}, Error);

  const LikelihoodField field(map);
  PointCloud2 points;
  points.points = {{0.1, 0.0}, {std::numeric_limits<double>::quiet_NaN(), 0.0}};
  EXPECT_THROW(field.scan_log_likelihood(points, SE2()), Error);
  points.points.pop_back();
  EXPECT_THROW(field.scan_log_likelihood(points, SE2(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0)), Error);
}

}  // namespace
}  // namespace slam2d
