// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/office_world.hpp"

#include <initializer_list>

namespace slam2d {

// Floor plan (m; x east, y north; not to scale). D: door opening (0.9 m), o: pillar.
//
//   y=20 +--------+--------+--------+-----------+
//        |   N1   |   N2   |   N3   |    N4     |
//   y=13 +---D----o---D----o---D----+-----D-----+
//        |   D         north corridor      D    |
//   y=11 | W |  +---D--------+---D----+  o|  E  |
//        |   |  |     C1     |   C2   |   D     |
//    y=7 |   |  +------------+--------+   |     |
//        |   D         south corridor     |     |
//    y=5 +------D--+------+------D----+----D----+
//        |   S1    D  S2  D   S3      D   S4    |
//    y=0 +---------+------+-----------+---------+
//       x=0  3  5  9     12 15     19  21        30
//
// Corridor ring: legs 2 m wide with centre lines x = 4, x = 20, y = 6, y = 12 (44 m around),
// around the central block C1 | C2 (x 5..19, y 7..11). Door centres:
//   y = 5:  S1 6.5, S3 18.0 (corridor); E-S4 25.5      x = 3:  W 6.0, 12.0
//   y = 13: N1 6.0, N2 11.0, N3 17.5 (corridor); E-N4 25.5   x = 21: E 8.0, 12.0
//   y = 11: C1 8.5, C2 15.5                            inner: S1-S2 (9, 2), S2-S3 (15, 2), S3-S4 (21, 3.5)
// The south corridor has no door from x = 7 to 17.5: a long, plain stretch. Pillars stand on the
// north corridor wall (x = 8, 14) and the east leg (y = 10.5); rooms hold desks, cabinets, pillars.
// Route: one plain lap of the ring (closes the loop), then a lap that detours through rooms
// S1 -> S2 -> S3, E and W (closes it again), ~110 m in all; the simulator repeats it.

namespace {

using Eigen::Vector2d;

constexpr double kDoorWidth = 0.9;  // m
constexpr double kPillarHalfWidth = 0.2;  // m

void add_segment(World& world, const Vector2d& a, const Vector2d& b) { world.walls.push_back({a, b}); }

/// The wall from a to b with door openings centred `doors` m from a (ascending).
void add_wall(World& world, const Vector2d& a, const Vector2d& b, std::initializer_list<double> doors = {}) {
  const Vector2d direction = (b - a).normalized();
  Vector2d start = a;
  for (const double door : doors) {
    add_segment(world, start, a + (door - 0.5 * kDoorWidth) * direction);
    start = a + (door + 0.5 * kDoorWidth) * direction;
  }
  add_segment(world, start, b);
}

void add_box(World& world, double x0, double y0, double x1, double y1) {
  add_segment(world, {x0, y0}, {x1, y0});
  add_segment(world, {x1, y0}, {x1, y1});
  add_segment(world, {x1, y1}, {x0, y1});
  add_segment(world, {x0, y1}, {x0, y0});
}

void add_pillar(World& world, double x, double y) {
  add_box(world, x - kPillarHalfWidth, y - kPillarHalfWidth, x + kPillarHalfWidth, y + kPillarHalfWidth);
}

void add_structure(World& world) {
  add_box(world, 0.0, 0.0, 30.0, 20.0);                  // outer walls
  add_wall(world, {0, 5}, {30, 5}, {6.5, 18.0, 25.5});    // S1, S3 to the corridor; S4 to E
  add_wall(world, {0, 13}, {30, 13}, {6.0, 11.0, 17.5, 25.5});  // N1..N3 to the corridor; N4 to E
  add_wall(world, {3, 5}, {3, 13}, {1.0, 7.0});            // W: doors at y = 6 and 12
  add_wall(world, {21, 5}, {21, 13}, {3.0, 7.0});          // E: doors at y = 8 and 12
  add_wall(world, {5, 7}, {19, 7});                        // central block, south side: plain
  add_wall(world, {5, 11}, {19, 11}, {3.5, 10.5});         // C1, C2 doors at x = 8.5, 15.5
  add_wall(world, {5, 7}, {5, 11});
  add_wall(world, {19, 7}, {19, 11});
  add_wall(world, {12, 7}, {12, 11});                      // C1 | C2
  add_wall(world, {9, 0}, {9, 5}, {2.0});                  // S1 | S2
  add_wall(world, {15, 0}, {15, 5}, {2.0});                // S2 | S3
  add_wall(world, {21, 0}, {21, 5}, {3.5});                // S3 | S4
  add_wall(world, {8, 13}, {8, 20});                       // N1 | N2
  add_wall(world, {14, 13}, {14, 20});                     // N2 | N3
  add_wall(world, {21, 13}, {21, 20});                     // N3 | N4
  add_pillar(world, 8.0, 13.0);                            // columns on the north corridor
  add_pillar(world, 14.0, 13.0);
  add_pillar(world, 21.0, 10.5);                           // and on the east leg
}

void add_furniture(World& world) {
  add_box(world, 1.0, 0.8, 3.0, 1.6);  // S1: desks, cabinet, pillar
  add_box(world, 1.0, 3.2, 3.0, 4.0);
  add_box(world, 8.4, 3.2, 8.9, 4.6);
  add_pillar(world, 4.5, 2.5);
  add_box(world, 10.5, 3.2, 13.5, 4.2);  // S2: table, cabinet
  add_box(world, 11.0, 0.0, 12.5, 0.5);
  add_box(world, 19.3, 0.5, 20.5, 1.5);  // S3
  add_pillar(world, 16.5, 4.0);
  add_box(world, 23.0, 1.0, 25.0, 2.5);  // S4
  add_box(world, 28.0, 0.5, 29.5, 4.0);
  add_box(world, 0.0, 6.5, 0.4, 11.5);   // W: shelves
  add_box(world, 26.0, 7.0, 28.5, 10.0);  // E: desk cluster, cabinets, pillar
  add_box(world, 29.5, 5.5, 30.0, 8.0);
  add_box(world, 22.0, 5.3, 23.5, 5.8);
  add_pillar(world, 23.0, 10.0);
  add_box(world, 1.0, 17.0, 3.0, 18.5);  // N1
  add_box(world, 5.0, 18.8, 7.5, 19.6);
  add_box(world, 9.5, 15.0, 12.5, 16.5);  // N2: conference table
  add_box(world, 15.0, 18.5, 17.0, 19.6);  // N3
  add_box(world, 19.0, 14.5, 20.5, 16.0);
  add_pillar(world, 17.5, 17.0);
  add_box(world, 23.0, 15.0, 27.0, 16.0);  // N4
  add_box(world, 28.8, 13.5, 29.6, 19.0);
  add_box(world, 7.0, 8.0, 10.0, 9.5);     // C1
  add_box(world, 13.0, 7.3, 14.5, 8.2);    // C2
  add_box(world, 16.5, 9.0, 18.5, 10.5);
}

}  // namespace

World make_office_world() {
  World world;
  world.name = "office";
  add_structure(world);
  add_furniture(world);
  world.bounds = Eigen::AlignedBox2d(Vector2d(0.0, 0.0), Vector2d(30.0, 20.0));
  world.route = {
      // Lap 1: the ring, counter-clockwise, back to the start.
      {4.0, 6.0}, {20.0, 6.0}, {20.0, 12.0}, {4.0, 12.0}, {4.0, 6.0},
      // Lap 2: through S1, S2, S3 (doors at (6.5, 5), (9, 2), (15, 2), (18, 5)) ...
      {6.5, 6.0}, {6.5, 2.0}, {18.0, 2.0}, {18.0, 6.0}, {20.0, 6.0},
      // ... through E (doors at (21, 8) and (21, 12)), along the north corridor into W
      // (door (3, 12)) and out of W (door (3, 6)) to the start.
      {20.0, 8.0}, {24.5, 8.0}, {24.5, 12.0}, {1.5, 12.0}, {1.5, 6.0}};
  return world;
}

}  // namespace slam2d
