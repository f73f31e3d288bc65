// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The simulated office runs the tests share, simulated once per test binary, and the hospital
// world's settings.

#include <cstdint>
#include <vector>

#include "slam2d/core/se2.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/sim/simulator.hpp"

namespace slam2d::test {

/// The office world driven for `duration` s with `seed` (everything else SimulationConfig's
/// defaults), simulated at the first call and kept for the later ones.
const SimulatedRun& simulated_office(double duration, std::uint64_t seed);

/// The hospital world driven as bench/datasets/hospital_world.yaml drives it (a scan every 0.2 m,
/// no return at 81.9 m, a good odometry) for `duration` s.
SimulationConfig hospital_simulation(double duration);

/// The run's odometry at its laser messages, stamped as the scans.
Trajectory odometry_of(const SimulatedRun& run);

/// The run's odometry poses at its laser messages, with a heading that drifts by `rate` rad per
/// metre driven forwards (Intel's wheel odometry: 0.06).
std::vector<SE2> odometry_with_heading_drift(const SimulatedRun& run, double rate);

}  // namespace slam2d::test
