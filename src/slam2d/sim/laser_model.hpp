// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A planar laser range finder in the style of a SICK LMS 200 as logged by CARMEN: beams over the
// field of view, Gaussian range noise, random dropouts, and "no return" reported as range_max.
// By default the scan is taken at one instant; with sweep_duration > 0 the beams are taken one
// after the other while the robot moves (motion distortion, for testing its correction).
//
// Beam angles follow the CARMEN FLASER convention, so a written log reads back with the same
// angles: angle_min = -field_of_view / 2; an even beam count splits the field of view into
// `beams` equal steps (180 beams: -90 deg .. +89 deg), an odd one puts beams at both ends
// (181 beams: -90 deg .. +90 deg).

#include <functional>
#include <numbers>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/sim/ray_caster.hpp"

namespace slam2d {

struct LaserModelConfig {
  int beams = 180;
  double field_of_view = std::numbers::pi;
  double range_max = 30.0;
  double range_noise_sigma = 0.01;
  double dropout_probability = 0.005;
  double rate_hz = 10.0;
  SE2 T_robot_sensor;  // the sensor's mounting pose on the robot (finite; not in the table)
  double sweep_duration = 0.0;
};

template <typename Fields>
void describe(Fields& f, LaserModelConfig& c) {
  f.number("beams", c.beams, "1", at_least(2), "beams per scan");
  f.number("field_of_view", c.field_of_view, "rad", open_closed(0, 2 * std::numbers::pi), "first to last beam");
  f.number("range_max", c.range_max, "m", greater_than(0), "no return (nothing hit, or a dropout) reads range_max");
  f.number("range_noise_sigma", c.range_noise_sigma, "m", at_least(0), "standard deviation of the Gaussian range noise");
  f.number("dropout_probability", c.dropout_probability, "1", between(0, 1), "chance that a beam returns nothing");
  f.number("rate_hz", c.rate_hz, "Hz", greater_than(0), "scans per second");
  f.number("sweep_duration", c.sweep_duration, "s", at_least(0), "first to last beam; 0 = all beams at the stamp");
}

/// Throws Error for beams < 2, a field of view outside (0, 2 pi], range_max <= 0, negative noise,
/// a dropout probability outside [0, 1], rate_hz <= 0, a negative sweep_duration, or non-finite values.
void validate(const LaserModelConfig& config);

/// Angle between beams (rad) by the convention above.
double beam_increment(const LaserModelConfig& config);

/// A scan from the robot pose T_world_robot, all beams at once (config.sweep_duration is ignored). Each beam draws its dropout and its noise from `rng`
/// in beam order (two draws per beam whatever happens), so the stream does not depend on the world.
LaserScan simulate_scan(const RayCaster& caster, const SE2& T_world_robot, double stamp,
                        const LaserModelConfig& config, Rng& rng);

/// A sweep taken while the robot moves: beam i is cast from T_world_robot_at(stamp + t_i), with
/// t_i = i * config.sweep_duration / (beams - 1). Same noise draws as simulate_scan; with
/// sweep_duration = 0 every beam is cast from T_world_robot_at(stamp), as simulate_scan does.
LaserScan simulate_sweep(const RayCaster& caster, const std::function<SE2(double)>& T_world_robot_at, double stamp,
                         const LaserModelConfig& config, Rng& rng);

}  // namespace slam2d
