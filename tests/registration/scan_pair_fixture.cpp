// SPDX-License-Identifier: BSD-3-Clause
#include "scan_pair_fixture.hpp"

#include <cmath>
#include <numbers>

#include "slam2d/core/rng.hpp"
#include "slam2d/sim/laser_model.hpp"
#include "slam2d/sim/ray_caster.hpp"

namespace slam2d::testing {
namespace {

void add_box(World& world, double x0, double y0, double x1, double y1) {
  world.walls.push_back({{x0, y0}, {x1, y0}});
  world.walls.push_back({{x1, y0}, {x1, y1}});
  world.walls.push_back({{x1, y1}, {x0, y1}});
  world.walls.push_back({{x0, y1}, {x0, y0}});
}

void finish(World& world) {
  world.bounds.setEmpty();
  for (const WallSegment& wall : world.walls) {
    world.bounds.extend(wall.a);
    world.bounds.extend(wall.b);
  }
}

}  // namespace

ScanPair make_scan_pair(const World& world, const ScanPairOptions& options) {
  LaserModelConfig laser;
  laser.beams = options.beams;
  laser.field_of_view = options.field_of_view;
  laser.range_max = options.range_max;
  laser.range_noise_sigma = options.range_sigma;
  laser.dropout_probability = options.dropout_probability;
  const RayCaster caster(world);
  Rng rng(options.seed);
  ScanPair pair;
  pair.T_target_source = options.T_target_source;
  pair.target_scan = simulate_scan(caster, options.T_world_target, 0.0, laser, rng);
  pair.source_scan = simulate_scan(caster, options.T_world_target * options.T_target_source, 0.1, laser, rng);
  pair.target = to_point_cloud(pair.target_scan, ScanFrame::kSensor).cloud;
  pair.source = to_point_cloud(pair.source_scan, ScanFrame::kSensor).cloud;
  return pair;
}

const World& office_world() {
  static const World world = make_world("office");
  return world;
}

const World& corridor_world() {
  static const World world = [] {
    World w;
    w.name = "corridor";
    w.walls.push_back({{-100.0, -1.0}, {100.0, -1.0}});
    w.walls.push_back({{-100.0, 1.0}, {100.0, 1.0}});
    w.route = {{-1.0, 0.0}, {1.0, 0.0}};
    finish(w);
    return w;
  }();
  return world;
}

const World& circular_room_world() {
  static const World world = [] {
    World w;
    w.name = "circular_room";
    constexpr int kSegments = 360;
    constexpr double kRadius = 5.0;
    for (int i = 0; i < kSegments; ++i) {
      const double a0 = 2.0 * std::numbers::pi * i / kSegments;
      const double a1 = 2.0 * std::numbers::pi * (i + 1) / kSegments;
      w.walls.push_back({{kRadius * std::cos(a0), kRadius * std::sin(a0)}, {kRadius * std::cos(a1), kRadius * std::sin(a1)}});
    }
    w.route = {{-1.0, 0.0}, {1.0, 0.0}};
    finish(w);
    return w;
  }();
  return world;
}

const World& room_world() {
  static const World world = [] {
    World w;
    w.name = "room";
    add_box(w, -4.0, -3.0, 4.0, 3.0);
    add_box(w, 1.5, 1.0, 1.8, 1.3);    // pillar
    add_box(w, -3.0, -2.8, -1.8, -2.0);  // desk against the south wall
    w.route = {{-1.0, 0.0}, {1.0, 0.0}};
    finish(w);
    return w;
  }();
  return world;
}

}  // namespace slam2d::testing
