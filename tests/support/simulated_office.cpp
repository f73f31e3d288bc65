// SPDX-License-Identifier: BSD-3-Clause
#include "support/simulated_office.hpp"

#include <map>
#include <utility>

namespace slam2d::test {

const SimulatedRun& simulated_office(double duration, std::uint64_t seed) {
  static std::map<std::pair<double, std::uint64_t>, SimulatedRun> runs;
  const auto key = std::make_pair(duration, seed);
  auto it = runs.find(key);
  if (it == runs.end()) {
    SimulationConfig config;
    config.duration = duration;
    config.seed = seed;
    it = runs.emplace(key, simulate(config)).first;
  }
  return it->second;
}

Trajectory odometry_of(const SimulatedRun& run) {
  Trajectory odometry;
  for (const LaserMessage* laser : laser_messages(run)) odometry.push_back(laser->scan.stamp, laser->odom_pose);
  return odometry;
}

std::vector<SE2> odometry_with_heading_drift(const SimulatedRun& run, double rate) {
  const std::vector<const LaserMessage*> lasers = laser_messages(run);
  std::vector<SE2> drifting;
  for (std::size_t i = 0; i < lasers.size(); ++i) {
    if (i == 0) {
      drifting.push_back(lasers.front()->odom_pose);
      continue;
    }
    const SE2 step = lasers[i - 1]->odom_pose.between(lasers[i]->odom_pose);
    drifting.push_back(drifting.back() * SE2(step.x(), step.y(), step.theta() + rate * step.x()));
  }
  return drifting;
}

SimulationConfig hospital_simulation(double duration) {
  SimulationConfig simulation;
  simulation.world = "hospital";
  simulation.duration = duration;
  simulation.speed = 0.4;
  simulation.laser.rate_hz = 2.0;
  simulation.laser.range_max = 81.9;
  simulation.odometry.scale_error = 0.002;
  simulation.odometry.heading_bias = 0.0005;
  return simulation;
}

}  // namespace slam2d::test
