// SPDX-License-Identifier: BSD-3-Clause
// Global localization in a building four times the simulated office: four copies of the office
// floor in a row (120 m x 20 m, ~2000 m^2 of free space), joined by doors, each copy with its own
// seeded crates. The copies are look-alikes: from the south corridor where the robot starts, the
// four floors differ only by their crates. With the default settings MCL (coarse grid search,
// then the particle filter), the Markov grid and the hybrid must converge to the truth and never
// report a localized pose at a wrong copy. Also the coarse search itself: the grid is sized by the
// map within its budget, finds the true pose, and is deterministic.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "slam2d/core/rng.hpp"
#include "slam2d/localization/global_search.hpp"
#include "slam2d/localization/hybrid.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/localization/session.hpp"
#include "slam2d/localization/sensor_model.hpp"
#include "slam2d/sim/simulator.hpp"
#include "slam2d/sim/world.hpp"

#include "localization/localization_run.hpp"

namespace slam2d {
namespace {

constexpr int kFloors = 4;
constexpr double kFloorLength = 30.0;  // m, the office's extent along x
constexpr double kDoorHalfWidth = 0.45;

// Removes the part of every vertical wall at x that crosses the door gap around (x, y).
void cut_door(World& world, double x, double y) {
  std::vector<WallSegment> walls;
  for (const WallSegment& w : world.walls) {
    const bool vertical = std::abs(w.a.x() - x) < 1e-9 && std::abs(w.b.x() - x) < 1e-9;
    const double lo = std::min(w.a.y(), w.b.y());
    const double hi = std::max(w.a.y(), w.b.y());
    if (!vertical || hi <= y - kDoorHalfWidth || lo >= y + kDoorHalfWidth) {
      walls.push_back(w);
      continue;
    }
    if (lo < y - kDoorHalfWidth) walls.push_back({{x, lo}, {x, y - kDoorHalfWidth}});
    if (hi > y + kDoorHalfWidth) walls.push_back({{x, y + kDoorHalfWidth}, {x, hi}});
  }
  world.walls = walls;
}

double distance_to_route(const World& world, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < world.route.size(); ++i) {
    best = std::min(best, distance_to_segment(p, world.route[i], world.route[(i + 1) % world.route.size()]));
  }
  return best;
}

// Crates (square boxes, 0.3-0.8 m) at seeded free places of each floor, off the route.
void add_crates(World& world, int per_floor, std::uint64_t seed) {
  Rng rng(seed);
  const World plain = world;
  for (int floor = 0; floor < kFloors; ++floor) {
    for (int placed = 0; placed < per_floor;) {
      const double half = rng.uniform(0.15, 0.4);
      const Eigen::Vector2d c(floor * kFloorLength + rng.uniform(0.5, kFloorLength - 0.5), rng.uniform(0.5, 19.5));
      if (distance_to_nearest_wall(plain, c) < half + 0.1 || distance_to_route(plain, c) < half + 0.6) continue;
      const Eigen::Vector2d a = c - Eigen::Vector2d(half, half);
      const Eigen::Vector2d b = c + Eigen::Vector2d(half, half);
      world.walls.push_back({{a.x(), a.y()}, {b.x(), a.y()}});
      world.walls.push_back({{b.x(), a.y()}, {b.x(), b.y()}});
      world.walls.push_back({{b.x(), b.y()}, {a.x(), b.y()}});
      world.walls.push_back({{a.x(), b.y()}, {a.x(), a.y()}});
      ++placed;
    }
  }
}

World make_building() {
  const World office = make_world("office");
  World world;
  world.name = "four-offices";
  for (int floor = 0; floor < kFloors; ++floor) {
    const Eigen::Vector2d shift(floor * kFloorLength, 0.0);
    for (const WallSegment& w : office.walls) world.walls.push_back({w.a + shift, w.b + shift});
  }
  // Doors between the floors on the north corridor's line (y = 12: the W and E rooms' doors).
  for (int floor = 1; floor < kFloors; ++floor) cut_door(world, floor * kFloorLength, 12.0);
  world.bounds = Eigen::AlignedBox2d(Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(kFloors * kFloorLength, 20.0));
  // Start in the second floor's south corridor, round its ring's east leg, then east along the
  // north corridors through the third floor into the fourth, and back.
  world.route = {{34.0, 6.0}, {50.0, 6.0}, {50.0, 12.0}, {110.0, 12.0}, {34.0, 12.0}};
  add_crates(world, 12, 7);
  return world;
}

const World& building() {
  static const World world = make_building();
  return world;
}

const SimulatedRun& building_run() {
  static const SimulatedRun run = [] {
    SimulationConfig config;
    config.duration = 100.0;
    config.seed = 11;
    return simulate(config, building());
  }();
  return run;
}

const LocalizationMap& building_map() {
  static const LocalizationMap map(rasterize_world(building(), 0.05));
  return map;
}

using RunResult = test::LocalizationRun;

RunResult run(Localizer& localizer) { return test::run_localization(localizer, building_run()); }

// Converged within `max_converge_s` s of data, every step from 5 s later near the truth, and no
// step reported localized more than 1 m from the truth (a look-alike floor is 30 m away).
void expect_global_localization(const RunResult& result, double max_converge_s) {
  ASSERT_TRUE(result.summary.converged_at_s.has_value()) << "never localized";
  EXPECT_LT(*result.summary.converged_at_s, max_converge_s);
  const std::size_t from = static_cast<std::size_t>((*result.summary.converged_at_s + 5.0) * 10.0);  // 10 Hz scans
  double sum = 0.0;
  double worst = 0.0;
  for (std::size_t i = from; i < result.errors.size(); ++i) {
    sum += result.errors[i];
    worst = std::max(worst, result.errors[i]);
  }
  ASSERT_LT(from, result.errors.size());
  EXPECT_LT(sum / static_cast<double>(result.errors.size() - from), 0.15);
  EXPECT_LT(worst, 0.6);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < result.errors.size(); ++i) wrong += result.localized[i] && result.errors[i] > 1.0 ? 1 : 0;
  EXPECT_EQ(wrong, 0u) << "steps reported localized more than 1 m from the truth";
}

TEST(LargeBuildingLocalization, TheWorldIsALargeBuildingOfLookAlikeFloors) {
  const LocalizationMap& map = building_map();
  const double free_area = static_cast<double>(map.free_cells().size()) * 0.05 * 0.05;
  EXPECT_GT(free_area, 1500.0);
  EXPECT_GE(building().bounds.sizes().x(), 100.0);
  // The robot passes from the second floor into the fourth.
  const SimulatedRun& sim = building_run();
  double max_x = 0.0;
  for (std::size_t i = 0; i < sim.truth.size(); ++i) max_x = std::max(max_x, sim.truth[i].pose.x());
  EXPECT_GT(max_x, 65.0);
}

TEST(LargeBuildingLocalization, MclWithDefaultSettingsLocalizesGlobally) {
  for (const std::uint64_t seed : {2u, 8u, 9u}) {  // seeds that converged at a wrong floor with weaker settings (docs)
    SCOPED_TRACE(seed);
    MonteCarloLocalization mcl(building_map(), MclConfig{.seed = seed});
    mcl.initialize_global();
    const RunResult result = run(mcl);
    expect_global_localization(result, 60.0);
    EXPECT_LT(mcl.particles().size(), 2000u) << "KLD-sampling shrinks the set once localized";
  }
}

// Same seed, same run; the particle budget holds even when it is smaller than the places.
TEST(LargeBuildingLocalization, MclGlobalStartIsDeterministicAndKeepsItsParticleBudget) {
  const auto lasers = laser_messages(building_run());
  for (const std::size_t budget : {std::size_t{50}, std::size_t{5000}}) {
    MonteCarloLocalization a(building_map(), MclConfig{.min_particles = 50, .max_particles = budget, .seed = 4});
    MonteCarloLocalization b(building_map(), MclConfig{.min_particles = 50, .max_particles = budget, .seed = 4});
    a.initialize_global();
    b.initialize_global();
    for (std::size_t i = 0; i < 100; ++i) {
      const LocalizationEstimate ea = a.update(lasers[i]->odom_pose, lasers[i]->scan);
      const LocalizationEstimate eb = b.update(lasers[i]->odom_pose, lasers[i]->scan);
      ASSERT_TRUE(ea.pose.is_approx(eb.pose, 0.0)) << "step " << i;
      ASSERT_LE(a.particles().size(), budget);
    }
    EXPECT_FALSE(a.searching());
  }
}

TEST(LargeBuildingLocalization, MarkovGridWithDefaultSettingsLocalizesGlobally) {
  MarkovGridLocalization markov(building_map());
  markov.initialize_global();
  expect_global_localization(run(markov), 60.0);
}

TEST(LargeBuildingLocalization, HybridWithDefaultSettingsLocalizesGlobally) {
  // Its grid is coarse (0.4 m, sigma 0.5 m): the crates that tell the floors apart weigh little.
  HybridLocalization hybrid(building_map());
  hybrid.initialize_global();
  expect_global_localization(run(hybrid), 90.0);
}

// The coarse pass alone: the grid fits the budget, and after a few scans its best hypothesis is
// the true pose to within the grid's step.
TEST(GlobalPoseSearch, TheGridIsSizedByTheFreeAreaWithinTheBudget) {
  const LocalizationMap& map = building_map();
  const GlobalPoseSearch fine(map, GlobalSearchConfig{});
  EXPECT_LE(fine.grid_poses(), GlobalSearchConfig{}.max_poses);
  EXPECT_EQ(fine.headings(), 72);
  const double free_area = static_cast<double>(map.free_cells().size()) * 0.05 * 0.05;
  EXPECT_NEAR(static_cast<double>(fine.positions()), free_area / (fine.step_xy() * fine.step_xy()), 0.1 * static_cast<double>(fine.positions()));
  const GlobalPoseSearch tight(map, GlobalSearchConfig{.max_poses = 200'000});
  EXPECT_LE(tight.grid_poses(), 200'000u);
  EXPECT_GT(tight.step_xy(), fine.step_xy()) << "a smaller budget takes a coarser grid";
  EXPECT_THROW(GlobalPoseSearch(map, GlobalSearchConfig{.step_xy = 0.0}), Error);
  EXPECT_THROW(GlobalPoseSearch(map, GlobalSearchConfig{.keep = 0}), Error);
}

TEST(GlobalPoseSearch, FindsTheTruePoseAndSeedsDeterministically) {
  const SimulatedRun& sim = building_run();
  const auto lasers = laser_messages(sim);
  GlobalPoseSearch search(building_map(), GlobalSearchConfig{.updates = 3});
  // Scans 4 s apart, the robot moving along its route.
  const SE2 T_odom_start = lasers[0]->odom_pose;
  std::size_t i = 0;
  for (; !search.done(); i += 40) {
    const ScanBeams beams = select_beams(lasers[i]->scan, 60, 30.0);
    search.add_scan(beams.points_robot, T_odom_start.between(lasers[i]->odom_pose));
  }
  const SE2 truth = sim.truth[i - 40].pose;
  // The best is the true pose, or the same pose on a look-alike floor (30 m along x).
  const SE2 best = search.best();
  const double floors = std::round((best.x() - truth.x()) / kFloorLength);
  EXPECT_LT((best.translation() - truth.translation() - Eigen::Vector2d(floors * kFloorLength, 0.0)).norm(), search.step_xy() + 0.1);
  EXPECT_LT(std::abs(std::remainder(best.theta() - truth.theta(), 2.0 * std::numbers::pi)), 0.1);
  // Places: the true one among them, each compact, the particles shared, the same for the same seed.
  Rng a(5);
  Rng b(5);
  const auto places_a = search.seed_places(5000, 200, 5000, 1.0, 0.5, a);
  const auto places_b = search.seed_places(5000, 200, 5000, 1.0, 0.5, b);
  ASSERT_EQ(places_a.size(), places_b.size());
  ASSERT_GE(places_a.size(), 2u) << "the look-alike floors are candidates too";
  EXPECT_LE(places_a.size(), 200u);
  std::size_t near = 0;
  bool true_place = false;
  for (std::size_t p = 0; p < places_a.size(); ++p) {
    true_place = true_place || (places_a[p][0].translation() - truth.translation()).norm() < 2.0 * search.step_xy();
    ASSERT_EQ(places_a[p].size(), places_b[p].size());
    EXPECT_EQ(places_a[p].size(), 5000 / places_a.size());
    for (std::size_t k = 0; k < places_a[p].size(); ++k) {
      EXPECT_TRUE(places_a[p][k].is_approx(places_b[p][k], 0.0));
      EXPECT_LT((places_a[p][k].translation() - places_a[p][0].translation()).norm(), 2.0 + search.step_xy());
      near += (places_a[p][k].translation() - truth.translation()).norm() < 0.5 ? 1 : 0;
    }
  }
  EXPECT_TRUE(true_place) << "the true place is a candidate";
  EXPECT_GT(near, 10u) << "the seeds cover the true pose";
}

}  // namespace
}  // namespace slam2d
