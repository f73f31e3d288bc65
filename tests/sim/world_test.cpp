// SPDX-License-Identifier: BSD-3-Clause
// Worlds: ray casting against hand-computed distances, the grid ray caster against brute force,
// and the office floor plan (route clearance, closure, rasterized map).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/sim/ray_caster.hpp"
#include "slam2d/sim/world.hpp"

namespace slam2d {
namespace {

using Eigen::Vector2d;
constexpr double kPi = std::numbers::pi;

// A 4 m x 2 m room with one diagonal wall from (3, 0) to (4, 1).
World tiny_world() {
  World world;
  world.name = "tiny";
  world.walls = {{{0, 0}, {4, 0}}, {{4, 0}, {4, 2}}, {{4, 2}, {0, 2}}, {{0, 2}, {0, 0}}, {{3, 0}, {4, 1}}};
  world.bounds = Eigen::AlignedBox2d(Vector2d(0, 0), Vector2d(4, 2));
  world.route = {{1, 1}, {2, 1}};
  return world;
}

TEST(CastRay, HandComputedDistancesInATinyWorld) {
  const World world = tiny_world();
  const Vector2d origin(1.0, 0.5);
  EXPECT_NEAR(*cast_ray(world, origin, 0.0, 10.0), 2.5, 1e-12);        // east: diagonal wall at x = 3.5
  EXPECT_NEAR(*cast_ray(world, origin, kPi / 2, 10.0), 1.5, 1e-12);    // north wall
  EXPECT_NEAR(*cast_ray(world, origin, -kPi / 2, 10.0), 0.5, 1e-12);   // south wall
  EXPECT_NEAR(*cast_ray(world, origin, kPi, 10.0), 1.0, 1e-12);        // west wall
  EXPECT_NEAR(*cast_ray(world, origin, kPi / 4, 10.0), 1.5 * std::sqrt(2.0), 1e-12);  // north wall at (2.5, 2)
  // From (1, 1) at 30 deg up: the north wall y = 2 at x = 1 + 1 / tan(30 deg).
  EXPECT_NEAR(*cast_ray(world, Vector2d(1, 1), kPi / 6, 10.0), 2.0, 1e-12);
  // Towards the diagonal wall from (3.5, 1.5) straight down: it is at y = 0.5.
  EXPECT_NEAR(*cast_ray(world, Vector2d(3.5, 1.5), -kPi / 2, 10.0), 1.0, 1e-12);
}

TEST(CastRay, NothingWithinMaxRangeOrOutsideIsNullopt) {
  const World world = tiny_world();
  EXPECT_FALSE(cast_ray(world, Vector2d(1.0, 0.5), 0.0, 2.4).has_value());
  EXPECT_TRUE(cast_ray(world, Vector2d(1.0, 0.5), 0.0, 2.5).has_value());  // exactly at max range counts
  EXPECT_FALSE(cast_ray(world, Vector2d(-1.0, 1.0), kPi, 100.0).has_value());  // outside, looking away
  EXPECT_NEAR(*cast_ray(world, Vector2d(-1.0, 1.0), 0.0, 100.0), 1.0, 1e-12);  // outside, looking in
  EXPECT_FALSE(cast_ray(World{}, Vector2d(0, 0), 0.0, 100.0).has_value());
}

TEST(IntersectRaySegment, EndPointsCountParallelRaysMiss) {
  const WallSegment wall{{1, -1}, {1, 1}};
  EXPECT_NEAR(*intersect_ray_segment({0, 0}, {1, 0}, wall), 1.0, 1e-15);
  EXPECT_NEAR(*intersect_ray_segment({0, 1}, {1, 0}, wall), 1.0, 1e-15);   // through the end point
  EXPECT_FALSE(intersect_ray_segment({0, 1.001}, {1, 0}, wall).has_value());
  EXPECT_FALSE(intersect_ray_segment({0, 0}, {0, 1}, wall).has_value());   // parallel
  EXPECT_FALSE(intersect_ray_segment({2, 0}, {1, 0}, wall).has_value());   // behind
  EXPECT_NEAR(*intersect_ray_segment({0, 0}, {2, 0}, wall), 0.5, 1e-15);   // t in units of |direction|
}

TEST(RayCaster, AgreesWithBruteForceOnRandomRays) {
  const World world = make_world("office");
  Rng rng(7);
  for (const double cell_size : {0.37, 1.0, 5.0}) {
    const RayCaster caster(world, cell_size);
    for (int i = 0; i < 4000; ++i) {
      // Mostly inside the building, some outside it; some rays start on a wall.
      Vector2d origin(rng.uniform(-3.0, 33.0), rng.uniform(-3.0, 23.0));
      if (i % 50 == 0) origin = world.walls[rng.uniform_index(world.walls.size())].a;
      const double angle = rng.uniform(-kPi, kPi);
      const double max_range = i % 3 == 0 ? 5.0 : 40.0;
      const auto expected = cast_ray(world, origin, angle, max_range);
      const auto actual = caster.cast(origin, angle, max_range);
      ASSERT_EQ(actual.has_value(), expected.has_value()) << "cell " << cell_size << " ray " << i;
      if (expected) {
        ASSERT_EQ(*actual, *expected) << "cell " << cell_size << " ray " << i;
      }
    }
  }
  // Axis-aligned rays along cell borders and walls.
  const RayCaster caster(world);
  for (double y = 0.0; y <= 20.0; y += 0.5) {
    for (const double angle : {0.0, kPi / 2, -kPi / 2, -kPi}) {
      const Vector2d origin(4.0, y);
      EXPECT_EQ(caster.cast(origin, angle, 40.0), cast_ray(world, origin, angle, 40.0)) << y << " " << angle;
    }
  }
}

TEST(Worlds, UnknownNameListsTheKnownOnes) {
  EXPECT_EQ(world_names(), (std::vector<std::string>{"office", "hospital"}));
  try {
    make_world("castle");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("castle"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("office"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("hospital"), std::string::npos);
  }
}

TEST(OfficeWorld, WallsLieInTheThirtyByTwentyFloor) {
  const World world = make_world("office");
  EXPECT_EQ(world.name, "office");
  EXPECT_NEAR(world.bounds.sizes().x(), 30.0, 1e-12);
  EXPECT_NEAR(world.bounds.sizes().y(), 20.0, 1e-12);
  EXPECT_GT(world.walls.size(), 100u);
  for (const WallSegment& wall : world.walls) {
    EXPECT_TRUE(world.bounds.contains(wall.a) && world.bounds.contains(wall.b));
    EXPECT_GT((wall.b - wall.a).norm(), 0.1);  // door openings leave no slivers
  }
}

TEST(OfficeWorld, RouteKeepsClearOfWalls) {
  const World world = make_world("office");
  ASSERT_GE(world.route.size(), 4u);
  const std::size_t n = world.route.size();
  double min_clearance = 1e9;
  for (std::size_t i = 0; i < n; ++i) {
    const Vector2d a = world.route[i], b = world.route[(i + 1) % n];  // closed: last -> first
    const int samples = static_cast<int>(std::ceil((b - a).norm() / 0.01));
    for (int k = 0; k <= samples; ++k) {
      const Vector2d p = a + (b - a) * (static_cast<double>(k) / samples);
      min_clearance = std::min(min_clearance, distance_to_nearest_wall(world, p));
    }
  }
  // Door openings are 0.9 m, so the centre line through a door clears the jambs by 0.45 m.
  EXPECT_GE(min_clearance, 0.35);
  EXPECT_NEAR(min_clearance, 0.45, 1e-3);
}

TEST(OfficeWorld, RouteIsAClosedTourThatPassesTheStartTwice) {
  const World world = make_world("office");
  const Vector2d start = world.route.front();
  int visits = 0;
  for (std::size_t i = 1; i < world.route.size(); ++i) visits += (world.route[i] - start).norm() < 1e-12 ? 1 : 0;
  EXPECT_EQ(visits, 1);  // lap 1 ends at the start, lap 2 ends there when the route closes
  EXPECT_NEAR((world.route.back() - start).norm(), 2.5, 1e-12);
  // The route rings the central block (x 5..19, y 7..11) twice, counter-clockwise: its winding
  // number around the block's centre is 2.
  const Vector2d centre(12.0, 9.0);
  double turned = 0.0;
  for (std::size_t i = 0; i < world.route.size(); ++i) {
    const Vector2d u = world.route[i] - centre, v = world.route[(i + 1) % world.route.size()] - centre;
    turned += std::atan2(u.x() * v.y() - u.y() * v.x(), u.dot(v));
  }
  EXPECT_NEAR(turned / (2.0 * kPi), 2.0, 1e-9);
  // The block is closed to the south: rays from its inside hit its walls.
  for (double angle = -kPi; angle < 0.0; angle += 0.1) {
    EXPECT_LT(*cast_ray(world, Vector2d(12.5, 9.0), angle, 30.0), 7.0);
  }
}

TEST(OfficeWorld, LongCorridorStretchIsPlain) {
  // Along the south corridor from x = 7 to 17.5, both side walls are 1 m away, without doors.
  const World world = make_world("office");
  for (double x = 7.0; x <= 17.5; x += 0.25) {
    EXPECT_NEAR(*cast_ray(world, Vector2d(x, 6.0), kPi / 2, 30.0), 1.0, 1e-12) << x;
    EXPECT_NEAR(*cast_ray(world, Vector2d(x, 6.0), -kPi / 2, 30.0), 1.0, 1e-12) << x;
  }
  // A door (S3 at x = 18) opens to the south: the ray runs into the room.
  EXPECT_GT(*cast_ray(world, Vector2d(18.0, 6.0), -kPi / 2, 30.0), 4.0);
}

TEST(HospitalWorld, TheRouteRunsDownTheMiddleOfACorridorRing) {
  const World world = make_world("hospital");
  EXPECT_EQ(world.name, "hospital");
  for (const WallSegment& wall : world.walls) {
    EXPECT_TRUE(world.bounds.contains(wall.a) && world.bounds.contains(wall.b));
  }
  // The closed route runs down the corridors' centre lines (2.4 m wide): no point of it is nearer
  // than 1.2 m to a wall.
  const std::size_t n = world.route.size();
  double length = 0.0, min_clearance = 1e9;
  for (std::size_t i = 0; i < n; ++i) {
    const Vector2d a = world.route[i], b = world.route[(i + 1) % n];
    length += (b - a).norm();
    for (double s = 0.0; s <= 1.0; s += 0.001) min_clearance = std::min(min_clearance, distance_to_nearest_wall(world, a + s * (b - a)));
  }
  EXPECT_NEAR(min_clearance, 1.2, 1e-9);
  EXPECT_NEAR(length, 2.0 * (77.6 + 27.6), 1e-9);
}

TEST(HospitalWorld, ThePlainStretchFixesTheRobotAcrossTheCorridorOnly) {
  // From x = 30 to 60 on the south corridor both walls are 1.2 m away without a recess, and the
  // corridor runs on beyond a 25 m usable range ahead: nothing in a scan's reach marks the
  // position along it.
  const World world = make_world("hospital");
  for (double x = 30.0; x <= 60.0; x += 0.25) {
    EXPECT_NEAR(*cast_ray(world, Vector2d(x, 1.2), kPi / 2, 30.0), 1.2, 1e-12) << x;
    EXPECT_NEAR(*cast_ray(world, Vector2d(x, 1.2), -kPi / 2, 30.0), 1.2, 1e-12) << x;
  }
  EXPECT_FALSE(cast_ray(world, Vector2d(35.0, 1.2), 0.0, 25.0).has_value());
  // A recess elsewhere (the outer wall's at x = 27) sets the wall back by 0.6 m.
  EXPECT_NEAR(*cast_ray(world, Vector2d(27.0, 1.2), -kPi / 2, 30.0), 1.8, 1e-12);
}

TEST(RasterizeWorld, WallsAreOccupiedAndTheRouteIsFree) {
  const World world = make_world("office");
  const OccupancyMap map = rasterize_world(world, 0.05);
  EXPECT_EQ(map.width, 602);  // 30 m + one cell each side
  EXPECT_EQ(map.height, 402);
  EXPECT_NEAR(map.origin.x(), -0.05, 1e-12);
  for (const WallSegment& wall : world.walls) {
    const Vector2d mid = 0.5 * (wall.a + wall.b);
    const Eigen::Vector2i cell = map.cell_of(mid);
    EXPECT_EQ(map.at(cell.x(), cell.y()), OccupancyMap::kOccupied);
  }
  for (const Vector2d& p : world.route) {
    const Eigen::Vector2i cell = map.cell_of(p);
    EXPECT_EQ(map.at(cell.x(), cell.y()), OccupancyMap::kFree);
  }
  EXPECT_THROW(rasterize_world(world, 0.0), Error);
  EXPECT_THROW(rasterize_world(world, std::nan("")), Error);
}

}  // namespace
}  // namespace slam2d

namespace slam2d {
namespace {

TEST(RayCaster, GarbageInputIsHandled) {
  World world = tiny_world();
  const RayCaster caster(world);
  EXPECT_FALSE(caster.cast(Vector2d(std::nan(""), 1.0), 0.0, 10.0).has_value());
  EXPECT_FALSE(caster.cast(Vector2d(1.0, 1.0), std::nan(""), 10.0).has_value());
  EXPECT_FALSE(caster.cast(Vector2d(1.0, 1.0), 0.0, std::nan("")).has_value());
  EXPECT_FALSE(caster.cast(Vector2d(1e300, 1.0), 0.0, 1e301).has_value());   // beyond, looking away
  EXPECT_NEAR(*caster.cast(Vector2d(-1e6, 1.0), 0.0, 2e6), 1e6, 1e-6);      // far away, looking in
  EXPECT_THROW(RayCaster(world, 0.0), Error);
  world.walls.push_back({{0, 0}, {std::numeric_limits<double>::infinity(), 0}});
  EXPECT_THROW(RayCaster{world}, Error);
  EXPECT_THROW(rasterize_world(world, 0.1), Error);
}

TEST(RasterizeWorld, WallsOutsideTheBoundsAreClipped) {
  World world = tiny_world();
  world.walls.push_back({{-1e12, 1.0}, {1e12, 1.0}});  // crosses the whole room at y = 1
  const OccupancyMap map = rasterize_world(world, 0.5);
  EXPECT_EQ(map.width, 10);  // 4 m / 0.5 m + one cell on each side
  EXPECT_EQ(map.height, 6);
  for (int ix = 0; ix < map.width; ++ix) EXPECT_EQ(map.at(ix, map.cell_of(Vector2d(0.0, 1.0)).y()), 100) << ix;
  EXPECT_EQ(map.at(3, 2), OccupancyMap::kFree);  // centre (1.25, 0.75): inside the room
}

}  // namespace
}  // namespace slam2d
