// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The "office" world: a made-up 30 m x 20 m office floor (no real building), drawn to have what
// real indoor logs have: a corridor ring around a central block, rooms with door openings,
// furniture and pillars, and one long, plain corridor stretch (a weakly constrained case for
// scan matching).

#include "slam2d/sim/world.hpp"

namespace slam2d {

/// Builds the office world (see office_world.cpp for the floor plan and the route).
World make_office_world();

}  // namespace slam2d
