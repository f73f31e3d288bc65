// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <variant>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/number_text.hpp"
#include "slam2d/sim/ray_caster.hpp"
#include "slam2d/sim/route_follower.hpp"

namespace slam2d {

namespace {

constexpr double kMaxMessages = 5e7;     // a bound on the run's size, against absurd rates
constexpr std::uint64_t kOdometryStream = 1;
constexpr std::uint64_t kLaserStream = 2;

// One run: the true robot, its odometry and its laser, advanced event by event.
class Simulation {
 public:
  Simulation(const SimulationConfig& config, const World& world)
      : config_(config),
        follower_(world.route, {.speed = config.speed,
                                .max_turn_rate = config.max_turn_rate,
                                .max_acceleration = config.max_acceleration}),
        caster_(world),
        root_rng_(config.seed),
        odometry_rng_(root_rng_.split(kOdometryStream)),
        laser_rng_(root_rng_.split(kLaserStream)) {
    T_world_robot_ = follower_.start_pose();
    odom_pose_ = T_world_robot_;
    truth_at_odom_ = T_world_robot_;
    run_.config = config;
    run_.config.world = world.name;
    const double scans = std::floor(config.duration * config.laser.rate_hz) + 1.0;
    const double odometry = std::floor(config.duration * config.odometry.rate_hz) + 1.0;
    run_.messages.reserve(static_cast<std::size_t>(2.0 * scans + odometry));
    run_.truth.reserve(static_cast<std::size_t>(scans));
  }

  SimulatedRun run();

 private:
  SE2 true_pose_at(double stamp) const;
  void odometry_tick(double stamp, const SE2& T_world_robot);
  void laser_tick(double stamp, const SE2& T_world_robot);

  SimulationConfig config_;
  RouteFollower follower_;
  RayCaster caster_;
  Rng root_rng_;      // only splits off the two streams below, in this order
  Rng odometry_rng_;
  Rng laser_rng_;
  double time_ = 0.0;          // s, time of the last control update
  SE2 T_world_robot_;          // the true pose at time_
  VelocityCommand command_;    // held since time_
  SE2 odom_pose_;              // T_odom_robot at the last ODOM
  SE2 truth_at_odom_;          // T_world_robot at the last ODOM
  SimulatedRun run_;
};

// Events at i / rate for each stream; equal stamps are bit-identical since i / rate is rounded once.
// The true state only advances at control updates, so ODOM and FLASER events (which read the
// pose in between) do not change it: the odometry is the same whatever the laser rate.
SimulatedRun Simulation::run() {
  const double dt_control = 1.0 / config_.control_rate_hz;
  std::uint64_t n_odom = 0, n_laser = 0, n_control = 0;
  while (true) {
    const double t_odom = static_cast<double>(n_odom) / config_.odometry.rate_hz;
    const double t_laser = static_cast<double>(n_laser) / config_.laser.rate_hz;
    const double t_control = static_cast<double>(n_control) / config_.control_rate_hz;
    if (std::min(t_odom, t_laser) > config_.duration) break;
    const double t = std::min({t_odom, t_laser, t_control});
    const SE2 T_world_robot = true_pose_at(t);
    if (t == t_odom) {
      odometry_tick(t, T_world_robot);
      ++n_odom;
    }
    if (t == t_laser) {
      laser_tick(t, T_world_robot);
      ++n_laser;
    }
    if (t == t_control) {
      T_world_robot_ = T_world_robot;
      time_ = t;
      command_ = follower_.update(T_world_robot_, command_, dt_control);
      ++n_control;
    }
  }
  return std::move(run_);
}

// The constant-velocity arc since the last control update: exp of the body twist (v, 0, omega) * dt.
SE2 Simulation::true_pose_at(double stamp) const {
  const double dt = stamp - time_;
  if (dt <= 0.0) return T_world_robot_;
  return T_world_robot_ * SE2::exp(Eigen::Vector3d(command_.v * dt, 0.0, command_.omega * dt));
}

void Simulation::odometry_tick(double stamp, const SE2& T_world_robot) {
  const SE2 odom_motion = corrupt_motion(truth_at_odom_.between(T_world_robot), config_.odometry, &odometry_rng_);
  odom_pose_ = odom_pose_ * odom_motion;
  truth_at_odom_ = T_world_robot;
  OdometryMessage message;
  message.reading.stamp = stamp;
  message.reading.pose = odom_pose_;
  message.reading.tv = odom_motion.translation().norm() * config_.odometry.rate_hz;
  message.reading.rv = odom_motion.theta() * config_.odometry.rate_hz;
  run_.messages.emplace_back(std::move(message));
}

void Simulation::laser_tick(double stamp, const SE2& T_world_robot) {
  const SE2 odom_now = odom_pose_ * corrupt_motion(truth_at_odom_.between(T_world_robot), config_.odometry, nullptr);
  LaserMessage laser;
  laser.type = "FLASER";
  // A sweep with duration keeps the current velocity command over its beams.
  laser.scan = simulate_sweep(
      caster_, [&](double t) { return t == stamp ? T_world_robot : true_pose_at(t); }, stamp, config_.laser, laser_rng_);
  laser.field_of_view = config_.laser.field_of_view;
  laser.laser_pose = odom_now;
  laser.odom_pose = odom_now;
  run_.messages.emplace_back(std::move(laser));
  run_.messages.emplace_back(TruePoseMessage{.stamp = stamp, .true_pose = T_world_robot, .odom_pose = odom_now});
  run_.truth.push_back(stamp, T_world_robot);
}

// Everything but the world name.
void validate_settings(const SimulationConfig& config) {
  check_fields(config, "SimulationConfig");
  validate(config.laser);  // T_robot_sensor
  const double events = config.duration * (config.control_rate_hz + config.odometry.rate_hz + config.laser.rate_hz);
  check(events <= kMaxMessages, "simulation: duration x rates is too large (more than 5e7 events)");
}

}  // namespace

void validate(const SimulationConfig& config) {
  const auto names = world_names();
  if (std::find(names.begin(), names.end(), config.world) == names.end()) {
    std::string known;
    for (const std::string& name : names) known += (known.empty() ? "" : ", ") + name;
    throw Error("simulation: unknown world '" + config.world + "' (known worlds: " + known + ")");
  }
  validate_settings(config);
}

SimulatedRun simulate(const SimulationConfig& config) {
  validate(config);
  return simulate(config, make_world(config.world));
}

SimulatedRun simulate(const SimulationConfig& config, const World& world) {
  validate_settings(config);
  for (const WallSegment& wall : world.walls) {
    check(wall.a.allFinite() && wall.b.allFinite(), "simulation: world '" + world.name + "' has a non-finite wall");
  }
  return Simulation(config, world).run();
}

std::vector<const LaserMessage*> laser_messages(const SimulatedRun& run) {
  std::vector<const LaserMessage*> lasers;
  for (const SensorMessage& message : run.messages) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) lasers.push_back(laser);
  }
  return lasers;
}

std::vector<std::string> run_comments(const SimulationConfig& config) {
  return {"slam2d simulated run: world " + config.world + ", seed " + std::to_string(config.seed) + ", duration " +
              format_number(config.duration) + " s",
          "FLASER and TRUEPOS carry the odometry pose; TRUEPOS also carries the true pose"};
}

}  // namespace slam2d
