// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A scan match as a measurement of motion, for fusion with the odometry (core/motion_fusion.hpp):
// the matcher's covariance (Censi 2007 or the Gauss-Newton Hessian), which counts only the range
// noise of correctly associated points and so is far too sure of itself, gets a floor added (a
// scan-to-scan or scan-to-map match is no better than the association and the map's cells allow)
// and, when the match is degenerate (degeneracy.hpp: a corridor's axis, a round room's heading),
// a large variance along its weak direction: there the odometry carries the motion.

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct MatchNoiseConfig {
  double floor_translation = 0.01;  // m, a standard deviation added in x and y
  double floor_rotation = 0.005;    // rad, ... in the heading
  double degenerate_sigma = 1.0;    // m (rad) along the unit weak direction (x, y, theta) of a degenerate match
};

template <typename Fields>
void describe(Fields& f, MatchNoiseConfig& c) {
  f.number("floor_translation", c.floor_translation, "m", at_least(0), "sigma added to the match's x and y");
  f.number("floor_rotation", c.floor_rotation, "rad", at_least(0), "sigma added to the match's heading");
  f.number("degenerate_sigma", c.degenerate_sigma, "m", at_least(0),
           "sigma added along the weak direction of a degenerate match");
}

/// The match T_target_source (in whatever frames the caller moved it into, e.g. the robots': see
/// match_between_robots) as a measurement: its covariance floored and inflated as above. A match
/// with unknown covariance stays unknown (it carries no information).
MotionMeasurement match_measurement(const MatchResult& match, const MatchNoiseConfig& config = {});

}  // namespace slam2d
