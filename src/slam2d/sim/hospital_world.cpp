// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/hospital_world.hpp"

#include <initializer_list>

namespace slam2d {

// Floor plan (m; x east, y north; not to scale). r: a door recess (1.2 m wide, 0.6 m deep).
//
//   y=30 +--r------r-----------r------------------r---------r--+
//        |                  north corridor                      |
// y=27.6 |  +---r---------------------r-----------------r----+  |
//        r  |                                                |  r
//        |  |              (the block: no way in)            |  |
//        r  |                                                |  |
//  y=2.4 |  +-----r---------r----------------------r------r--+  |
//        |                  south corridor                      |
//    y=0 +----r-----r------r----------------------------r----r--+
//       x=0                 30                       60        80
//
// Corridor legs 2.4 m wide, centre lines y = 1.2, y = 28.8, x = 1.2, x = 78.8. The south corridor
// has no recess on either wall from x = 30 to 60: at 1.2 m from both walls a 180-degree laser sees
// two parallel lines there, and the corridor's end is 20-50 m ahead. The recesses elsewhere are
// spaced unevenly so that no two stretches look alike. Route: the ring, counter-clockwise, from the
// south-west corner (one lap 210 m; the simulator repeats it).

namespace {

using Eigen::Vector2d;

constexpr double kRecessHalfWidth = 0.6;  // m
constexpr double kRecessDepth = 0.6;      // m

/// The wall from a to b with recesses centred `recesses` m from a (ascending), each set back by
/// kRecessDepth on the side of `outward` (a unit normal to the wall).
void add_wall(World& world, const Vector2d& a, const Vector2d& b, const Vector2d& outward,
              std::initializer_list<double> recesses) {
  const Vector2d direction = (b - a).normalized();
  const Vector2d back = kRecessDepth * outward;
  Vector2d start = a;
  for (const double centre : recesses) {
    const Vector2d left = a + (centre - kRecessHalfWidth) * direction;
    const Vector2d right = a + (centre + kRecessHalfWidth) * direction;
    world.walls.push_back({start, left});
    world.walls.push_back({left, left + back});
    world.walls.push_back({left + back, right + back});
    world.walls.push_back({right + back, right});
    start = right;
  }
  world.walls.push_back({start, b});
}

}  // namespace

World make_hospital_world() {
  constexpr double kLength = 80.0, kWidth = 30.0, kCorridor = 2.4;
  World world;
  world.name = "hospital";
  const Vector2d south(0, -1), north(0, 1), west(-1, 0), east(1, 0);
  // Outer walls (recesses face out of the ring).
  add_wall(world, {0, 0}, {kLength, 0}, south, {4.0, 9.5, 17.0, 27.0, 63.5, 75.0});
  add_wall(world, {kLength, 0}, {kLength, kWidth}, east, {7.0, 19.5});
  add_wall(world, {kLength, kWidth}, {0, kWidth}, north, {6.0, 14.5, 31.0, 52.0, 77.0});
  add_wall(world, {0, kWidth}, {0, 0}, west, {9.0, 21.0});
  // The central block (recesses face into the block).
  const double lo = kCorridor, hi_x = kLength - kCorridor, hi_y = kWidth - kCorridor;
  add_wall(world, {lo, lo}, {hi_x, lo}, north, {6.5, 12.0, 60.5, 68.0});
  add_wall(world, {hi_x, lo}, {hi_x, hi_y}, west, {});
  add_wall(world, {hi_x, hi_y}, {lo, hi_y}, south, {11.0, 38.5, 57.0});
  add_wall(world, {lo, hi_y}, {lo, lo}, east, {});
  world.bounds = Eigen::AlignedBox2d(Vector2d(-kRecessDepth, -kRecessDepth),
                                     Vector2d(kLength + kRecessDepth, kWidth + kRecessDepth));
  const double c = 0.5 * kCorridor;
  world.route = {{c, c}, {kLength - c, c}, {kLength - c, kWidth - c}, {c, kWidth - c}};
  return world;
}

}  // namespace slam2d
