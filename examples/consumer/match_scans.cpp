// SPDX-License-Identifier: BSD-3-Clause
// Match two scans: two simulated scans of the office world, 0.3 m and 0.1 rad apart, matched
// with PL-ICP from the identity. Prints the recovered motion; exits 1 if it is off by more than
// 1 cm or 0.5 degrees.
#include <cmath>
#include <cstdio>
#include <numbers>

#include <slam2d/core/laser_scan.hpp>
#include <slam2d/core/rng.hpp>
#include <slam2d/methods/matcher_registry.hpp>
#include <slam2d/sim/laser_model.hpp>
#include <slam2d/sim/office_world.hpp>
#include <slam2d/sim/ray_caster.hpp>

int main() {
  using namespace slam2d;
  const World world = make_office_world();
  const RayCaster caster(world);
  const Eigen::Vector2d start = world.route[0];
  const Eigen::Vector2d ahead = world.route[1] - start;
  const SE2 T_world_a(start.x(), start.y(), std::atan2(ahead.y(), ahead.x()));
  const SE2 T_a_b(0.3, 0.05, 0.1);  // the motion to recover
  Rng rng(1);
  const LaserModelConfig laser;  // 180 beams over 180 degrees, 1 cm of range noise
  const LaserScan a = simulate_scan(caster, T_world_a, 0.0, laser, rng);
  const LaserScan b = simulate_scan(caster, T_world_a * T_a_b, 0.1, laser, rng);

  const Matcher match = make_matcher("pl-icp");
  const MatchResult result = match(to_point_cloud(a).cloud, to_point_cloud(b).cloud, SE2());
  const SE2 error = T_a_b.inverse() * result.T_target_source;
  std::printf("pl-icp: x %.4f m  y %.4f m  theta %.4f rad (truth 0.3, 0.05, 0.1); %d iterations, %zu inliers\n",
              result.T_target_source.x(), result.T_target_source.y(), result.T_target_source.theta(),
              result.iterations, result.inliers);
  const bool ok = error.translation().norm() < 0.01 && std::abs(error.theta()) < 0.5 * std::numbers::pi / 180.0;
  std::printf("%s\n", ok ? "recovered" : "NOT recovered");
  return ok ? 0 : 1;
}
