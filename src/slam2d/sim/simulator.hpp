// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Simulated robot runs: a differential-drive robot follows a world's route (route_follower.hpp),
// its wheel odometry drifts (odometry_model.hpp) and its laser scans the walls (laser_model.hpp).
// The output is a sensor log in memory (core/sensor_log.hpp), in the file order of a raw CARMEN
// log, plus the true trajectory.
//
// Deterministic: for a given config the run is identical on every platform. All randomness comes
// from Rng(seed), split into one stream for the odometry noise and one for the laser, so changing
// the laser settings does not change the odometry, and the true motion never depends on the seed.
//
// Timing: ODOM every 1 / odometry.rate_hz s and FLASER + TRUEPOS every 1 / laser.rate_hz s, both
// from t = 0 to t = duration; an ODOM with the same stamp as a FLASER comes first. The robot's
// velocity command is updated every 1 / control_rate_hz s and held in between; the true pose
// follows the exact constant-velocity arc. The odometry starts at the true start pose (the
// odometry frame is the world frame at t = 0) and is integrated over each ODOM interval; a scan
// between two ODOM messages gets the last one plus the noise-free part of the motion since.
// With laser.sweep_duration > 0 the beams of a scan are taken over that time along the robot's
// constant-velocity arc (the command held at the scan's stamp); TRUEPOS is the pose at the stamp.

#include <cstdint>
#include <string>
#include <vector>

#include "slam2d/core/trajectory.hpp"
#include "slam2d/core/sensor_log.hpp"
#include "slam2d/sim/laser_model.hpp"
#include "slam2d/sim/odometry_model.hpp"
#include "slam2d/sim/world.hpp"

namespace slam2d {

struct SimulationConfig {
  std::string world = "office";  // a make_world name (ignored by the overload taking a World); not in the table
  double duration = 240.0;
  std::uint64_t seed = 1;
  double speed = 0.6;
  double max_turn_rate = 1.0;
  double max_acceleration = 0.5;
  double control_rate_hz = 100.0;
  LaserModelConfig laser;
  OdometryModelConfig odometry;
};

template <typename Fields>
void describe(Fields& f, SimulationConfig& c) {
  f.number("duration", c.duration, "s", between(0, 1e5), "simulated time");
  f.number("seed", c.seed, "1", any_value(), "of every random stream");
  f.number("speed", c.speed, "m/s", greater_than(0), "cruise speed");
  f.number("max_turn_rate", c.max_turn_rate, "rad/s", greater_than(0), "fastest turn");
  f.number("max_acceleration", c.max_acceleration, "m/s^2", greater_than(0), "largest change of speed");
  f.number("control_rate_hz", c.control_rate_hz, "Hz", greater_than(0), "velocity command updates");
  f.section("laser", c.laser, "the simulated laser range finder");
  f.section("odometry", c.odometry, "the simulated wheel odometry");
}

struct SimulatedRun {
  SimulationConfig config;              // what made this run
  std::vector<SensorMessage> messages;  // file order: ODOM, FLASER, TRUEPOS; stamps from 0, never decreasing
  Trajectory truth;                     // the true pose T_world_robot at each scan's stamp
};

/// Throws Error for invalid settings (non-finite or out-of-range values, an unknown world).
void validate(const SimulationConfig& config);

/// Runs the simulation in the world named by config.world.
SimulatedRun simulate(const SimulationConfig& config);
/// Runs the simulation in a given world (its route must have >= 2 distinct points).
SimulatedRun simulate(const SimulationConfig& config, const World& world);

/// The run's laser messages, in order (pointers into run.messages).
std::vector<const LaserMessage*> laser_messages(const SimulatedRun& run);

/// The comment lines that say how a run was made (world, seed, duration), for the head of its log:
/// write_carmen_log(path, run_comments(run.config), run.messages) (io/carmen_log.hpp).
std::vector<std::string> run_comments(const SimulationConfig& config);

}  // namespace slam2d
