// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The simulated office runs the tests share, simulated once per test binary.

#include <cstdint>

#include "slam2d/sim/simulator.hpp"

namespace slam2d::test {

/// The office world driven for `duration` s with `seed` (everything else SimulationConfig's
/// defaults), simulated at the first call and kept for the later ones.
const SimulatedRun& simulated_office(double duration, std::uint64_t seed);

}  // namespace slam2d::test
