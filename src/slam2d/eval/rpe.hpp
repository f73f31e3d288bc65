// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Relative pose error (RPE) of J. Sturm, N. Engelhard, F. Endres, W. Burgard, D. Cremers:
// "A benchmark for the evaluation of RGB-D SLAM systems", IROS 2012, Sec. VI-B, Eq. (1)-(2), in
// 2D, with the window measured either in time (as in the paper) or in travelled distance (as in
// the KITTI odometry benchmark, Geiger et al. CVPR 2012).
//
// Poses are associated by stamp and ordered by stamp. For each associated pose i, j is the first
// later pose at least `delta` further along; the error is
// E_ij = (Ref_i^-1 Ref_j)^-1 (Est_i^-1 Est_j), summarised by |t(E)| (m) and |angle(E)| (deg).

#include <array>
#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/trajectory.hpp"

namespace slam2d {

enum class RpeWindow {
  kDistance,  // delta is path length (m) along the associated reference poses
  kTime,      // delta is a stamp difference (s)
};
constexpr auto choices(RpeWindow) {
  return std::array{Choice{"distance", RpeWindow::kDistance}, Choice{"time", RpeWindow::kTime}};
}

struct RpeConfig {
  RpeWindow window = RpeWindow::kDistance;
  double delta = 1.0;
  double stamp_tolerance = 0.001;
};

template <typename Fields>
void describe(Fields& f, RpeConfig& c) {
  f.choice("window", c.window, "how \"further along\" is measured: path length or time");
  f.number("delta", c.delta, "m (distance) or s (time)", greater_than(0), "the window length");
  f.number("stamp_tolerance", c.stamp_tolerance, "s", at_least(0),
           "each estimate pose is matched to the reference pose with the nearest stamp within this");
}

struct RpeStatistics {
  double rmse = 0.0;
  double mean = 0.0;
  double max = 0.0;
};

/// One window's error.
struct RpeWindowError {
  double stamp_from = 0.0;   // s, the estimate's stamp at i
  double stamp_to = 0.0;     // s, ... at j
  double translation = 0.0;  // m, |t(E_ij)|
  double rotation_deg = 0.0; // deg, |angle(E_ij)|
};

struct RpeResult {
  std::size_t matched = 0;     // associated pose pairs
  std::size_t pairs = 0;       // (i, j) windows evaluated
  RpeStatistics translation;   // m
  RpeStatistics rotation_deg;  // deg
  std::vector<RpeWindowError> errors;  // one per window, in stamp order
};

/// RPE of `estimate` against `reference`. Statistics are zero when no window fits (pairs == 0).
/// Throws Error on delta <= 0 or non-finite, a bad tolerance or non-finite trajectory values.
RpeResult relative_pose_error(const Trajectory& estimate, const Trajectory& reference, const RpeConfig& config = {});

}  // namespace slam2d
