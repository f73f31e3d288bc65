// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The first step of the 2015 precise-indoor-localization pipeline (R. Kaijaluoto, A. Kukko,
// J. Hyyppa, "Precise indoor localization for mobile laser scanner", ISPRS Archives XL-4/W5,
// 2015): Hector SLAM's dense trajectory becomes the odometry of a sparse, globally consistent
// method, but a scan-to-map matcher occasionally jumps (a wrong match, then back). Odometry does
// not jump, so large discontinuities are replaced by the mean of the preceding transforms.
//
// With step i the relative motion d_i = T_{i-1}^-1 T_i and m the mean of the `window` steps kept
// before it (their x, y and theta averaged):
//   step i is a discontinuity when |t(d_i)| > max(min_jump, factor |t(m)|) or
//   |theta(d_i)| > max(min_turn, factor |theta(m)|);
//   it is then replaced by m and the trajectory after it re-integrated, so every later pose keeps
//   its own increments.
// Steps are counted per scan, not per second: a logger's stamps may bunch scans (Intel's: 38% of
// its steps are under 20 ms), and the scanner's rate is what bounds a step. A step over more than
// max_dt (a gap in the log) is kept as it is and does not enter the mean.

#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/trajectory.hpp"

namespace slam2d {

struct DiscontinuitySmoothingConfig {
  // Chosen leave-one-out on Hector's laser-only trajectories of the three public logs, a step
  // labelled a jump where it differs from graph SLAM's (with odometry) by 0.1 m or 0.1 rad:
  // picked on ACES + FR079 and on Intel + ACES (the same values), checked on the third; no
  // false jump on Intel or FR079, 8 of 7373 steps on ACES (docs/methods/fusion.md).
  std::size_t window = 10;
  double factor = 3.0;
  double min_jump = 0.25;
  double min_turn = 0.5;
  double max_dt = 1.0;
};

template <typename Fields>
void describe(Fields& f, DiscontinuitySmoothingConfig& c) {
  f.number("window", c.window, "steps", at_least(1), "the preceding steps whose mean motion replaces a jump");
  f.number("factor", c.factor, "1", greater_than(1), "a step longer than this times the window's mean step ...");
  f.number("min_jump", c.min_jump, "m", greater_than(0), "... and longer than this is a jump");
  f.number("min_turn", c.min_turn, "rad", greater_than(0), "the same bound on the step's turn");
  f.number("max_dt", c.max_dt, "s", greater_than(0), "steps over a longer time (a gap in the log) are kept as they are");
}

void validate(const DiscontinuitySmoothingConfig& config);

struct SmoothingResult {
  Trajectory trajectory;            // same stamps and order as the input
  std::vector<std::size_t> jumps;   // indices i of the steps (i-1 -> i) replaced
};

/// The trajectory with its discontinuities replaced. The input is taken in its order (a log's
/// scan order).
SmoothingResult smooth_discontinuities(const Trajectory& dense, const DiscontinuitySmoothingConfig& config = {});

}  // namespace slam2d
