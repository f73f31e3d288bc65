// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The "hospital" world: one long corridor ring (80 m x 30 m, 2.4 m wide, 210 m around), drawn to
// have what long institutional logs have and the office lacks: corridors longer than a laser's
// reach along them, with door recesses as the only features and a 30 m stretch with none (the
// scan fixes the robot across the corridor and in heading, the odometry alone along it), and one
// loop that closes only after a lap.

#include "slam2d/sim/world.hpp"

namespace slam2d {

/// Builds the hospital world (see hospital_world.cpp for the floor plan and the route).
World make_hospital_world();

}  // namespace slam2d
