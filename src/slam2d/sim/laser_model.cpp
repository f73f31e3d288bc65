// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/laser_model.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

void validate(const LaserModelConfig& config) {
  check_fields(config, "LaserModelConfig");
  check(config.T_robot_sensor.vector().allFinite(), "LaserModelConfig: T_robot_sensor must be finite");
}

double beam_increment(const LaserModelConfig& config) {
  const int steps = config.beams % 2 == 1 ? config.beams - 1 : config.beams;
  return config.field_of_view / static_cast<double>(steps);
}

LaserScan simulate_scan(const RayCaster& caster, const SE2& T_world_robot, double stamp,
                        const LaserModelConfig& config, Rng& rng) {
  LaserModelConfig instantaneous = config;
  instantaneous.sweep_duration = 0.0;
  return simulate_sweep(caster, [&T_world_robot](double) { return T_world_robot; }, stamp, instantaneous, rng);
}

LaserScan simulate_sweep(const RayCaster& caster, const std::function<SE2(double)>& T_world_robot_at, double stamp,
                         const LaserModelConfig& config, Rng& rng) {
  LaserScan scan;
  scan.stamp = stamp;
  scan.angle_min = -0.5 * config.field_of_view;
  scan.angle_increment = beam_increment(config);
  scan.range_min = 0.0;
  scan.range_max = config.range_max;
  scan.T_robot_sensor = config.T_robot_sensor;
  scan.ranges.resize(static_cast<std::size_t>(config.beams));
  const double beam_interval = config.sweep_duration / static_cast<double>(config.beams - 1);  // s
  SE2 T_world_sensor = T_world_robot_at(stamp) * config.T_robot_sensor;
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    if (config.sweep_duration > 0.0 && i > 0) {
      T_world_sensor = T_world_robot_at(stamp + static_cast<double>(i) * beam_interval) * config.T_robot_sensor;
    }
    const bool dropout = rng.bernoulli(config.dropout_probability);
    const double noise = rng.gaussian(0.0, config.range_noise_sigma);
    const auto hit = caster.cast(T_world_sensor.translation(), T_world_sensor.theta() + scan.angle(i), config.range_max);
    if (!hit || dropout) {
      scan.ranges[i] = config.range_max;
      continue;
    }
    scan.ranges[i] = std::clamp(*hit + noise, 0.0, config.range_max);
  }
  return scan;
}

}  // namespace slam2d
