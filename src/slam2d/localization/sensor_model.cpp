// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/error.hpp"
#include "slam2d/grid/ray_casting.hpp"

namespace slam2d {

ScanBeams select_beams(const LaserScan& scan, int max_beams, double usable_range) {
  check(max_beams > 0, "localization: the number of beams must be positive");
  ScanBeams beams;
  beams.T_robot_sensor = scan.T_robot_sensor;
  beams.range_max = std::min(scan.range_max, usable_range);
  const std::size_t n = scan.size();
  const std::size_t kept = std::min<std::size_t>(n, static_cast<std::size_t>(max_beams));
  beams.points_robot.reserve(kept);
  beams.ranges.reserve(kept);
  beams.bearings.reserve(kept);
  for (std::size_t k = 0; k < kept; ++k) {
    const std::size_t i = kept == 1 ? n / 2 : k * (n - 1) / (kept - 1);
    const double range = scan.ranges[i];
    if (!std::isfinite(range) || range < scan.range_min) continue;
    const double angle = scan.angle(i);
    if (range >= beams.range_max) {
      beams.ranges.push_back(beams.range_max);
      beams.bearings.push_back(angle);
      continue;
    }
    beams.ranges.push_back(range);
    beams.bearings.push_back(angle);
    beams.points_robot.push_back(scan.T_robot_sensor.act(Eigen::Vector2d(range * std::cos(angle), range * std::sin(angle))));
  }
  return beams;
}

void validate(const BeamModelConfig& config) {
  check_fields(config, "BeamModelConfig");
  check(config.z_hit + config.z_short + config.z_max + config.z_rand > 0.0, "BeamModelConfig: all weights are zero");
}

double cast_ray(const OccupancyMap& map, const Eigen::Vector2d& origin, double angle, double max_range) {
  // Cells in the map's own axes.
  const SE2 T_cells_map = map.origin.inverse();
  const Eigen::Vector2d from = T_cells_map.act(origin) / map.resolution;
  const double local_angle = angle - map.origin.theta();
  const Eigen::Vector2d to = from + (max_range / map.resolution) * Eigen::Vector2d(std::cos(local_angle), std::sin(local_angle));
  const CellIndex start{static_cast<int>(std::floor(from.x())), static_cast<int>(std::floor(from.y()))};
  const CellIndex end{static_cast<int>(std::floor(to.x())), static_cast<int>(std::floor(to.y()))};
  double hit = max_range;
  bool found = false;
  // Walk until the first occupied cell; the callback cannot stop the walk, so it ignores the rest.
  for_each_cell_before(start, end, [&](CellIndex cell) {
    if (found || !map.contains(cell.x, cell.y) || map.at(cell.x, cell.y) < 65) return;
    found = true;
    const Eigen::Vector2d centre(cell.x + 0.5, cell.y + 0.5);
    hit = std::min(max_range, (centre - from).norm() * map.resolution);
  });
  return hit;
}

double beam_model_log_likelihood(const OccupancyMap& map, const ScanBeams& beams, const SE2& T_map_robot,
                                 const BeamModelConfig& config) {
  const double total = config.z_hit + config.z_short + config.z_max + config.z_rand;
  const SE2 T_map_sensor = T_map_robot * beams.T_robot_sensor;
  const double z_max = beams.range_max;
  double log_likelihood = 0.0;
  for (std::size_t k = 0; k < beams.ranges.size(); ++k) {
    const double z = beams.ranges[k];
    const double expected = cast_ray(map, T_map_sensor.translation(), T_map_sensor.theta() + beams.bearings[k], z_max);
    // p_hit: the Gaussian around z*, normalised over [0, z_max] (Eq. 6.4 - 6.6).
    const double sqrt2_sigma = std::sqrt(2.0) * config.sigma_hit;
    const double eta_hit = 0.5 * (std::erf((z_max - expected) / sqrt2_sigma) - std::erf(-expected / sqrt2_sigma));
    const double d = z - expected;
    const double p_hit = z < z_max ? std::exp(-d * d / (2.0 * config.sigma_hit * config.sigma_hit)) /
                                         (std::sqrt(2.0 * std::numbers::pi) * config.sigma_hit * std::max(eta_hit, 1e-9))
                                   : 0.0;
    // p_short: exponential below z* (Eq. 6.7 - 6.9).
    const double p_short = z <= expected ? config.lambda_short * std::exp(-config.lambda_short * z) /
                                               (1.0 - std::exp(-config.lambda_short * expected) + 1e-12)
                                         : 0.0;
    // p_max: a point mass, smoothed over a band below z_max (Eq. 6.10); p_rand: uniform (Eq. 6.11).
    const double band = std::max(config.max_range_band, 1e-3);
    const double p_max = z >= z_max - band ? 1.0 / band : 0.0;
    const double p_rand = z < z_max ? 1.0 / z_max : 0.0;
    const double p = (config.z_hit * p_hit + config.z_short * p_short + config.z_max * p_max + config.z_rand * p_rand) / total;
    log_likelihood += std::log(std::max(p, 1e-300));
  }
  return log_likelihood;
}

}  // namespace slam2d
