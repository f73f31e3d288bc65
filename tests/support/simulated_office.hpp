// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The simulated office runs the tests share, simulated once per test binary.

#include <cstdint>
#include <vector>

#include "slam2d/core/se2.hpp"
#include "slam2d/sim/simulator.hpp"

namespace slam2d::test {

/// The office world driven for `duration` s with `seed` (everything else SimulationConfig's
/// defaults), simulated at the first call and kept for the later ones.
const SimulatedRun& simulated_office(double duration, std::uint64_t seed);

/// The run's odometry poses at its laser messages, with a heading that drifts by `rate` rad per
/// metre driven forwards (Intel's wheel odometry: 0.06).
std::vector<SE2> odometry_with_heading_drift(const SimulatedRun& run, double rate);

}  // namespace slam2d::test
