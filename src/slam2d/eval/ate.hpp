// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Absolute trajectory error (ATE) of J. Sturm, N. Engelhard, F. Endres, W. Burgard, D. Cremers:
// "A benchmark for the evaluation of RGB-D SLAM systems", IROS 2012, Sec. VI-A, in 2D: poses are
// associated by stamp, the estimate is aligned to the reference by the rigid motion (rotation +
// translation, no scale) that minimises the squared position errors (Horn 1987 / Umeyama 1991,
// closed form in 2D), and the remaining position errors are summarised.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/trajectory.hpp"

namespace slam2d {

struct AteConfig {
  double stamp_tolerance = 0.001;
};

template <typename Fields>
void describe(Fields& f, AteConfig& c) {
  f.number("stamp_tolerance", c.stamp_tolerance, "s", at_least(0),
           "each estimate pose is matched to the reference pose with the nearest stamp within this");
}

struct AteResult {
  std::size_t matched = 0;     // associated pose pairs
  SE2 T_reference_estimate;    // aligns the estimate's world frame to the reference's
  double rmse = 0.0;           // m, of the translational errors after alignment
  double mean = 0.0;           // m
  double median = 0.0;         // m
  double max = 0.0;            // m
  std::vector<double> errors;  // m, one per associated pair, in stamp order
  std::vector<std::size_t> estimate_indices;  // into the estimate, the pose of each of those pairs
};

/// ATE of `estimate` against `reference`. Throws Error when fewer than two poses associate (the
/// alignment would be undetermined), on a bad tolerance or on non-finite values.
AteResult absolute_trajectory_error(const Trajectory& estimate, const Trajectory& reference,
                                    const AteConfig& config = {});

/// The rigid motion T_target_source minimising sum_i |T * source_i - target_i|^2 (Umeyama 1991,
/// Eq. (40)-(41), without scale; in 2D the rotation angle has the closed form
/// atan2(sum cross(s_i, t_i), sum dot(s_i, t_i)) over centred points). When every source point
/// coincides, any rotation is optimal and the angle returned is 0. Throws Error on empty input or
/// sizes that differ.
SE2 align_rigid_2d(const std::vector<Eigen::Vector2d>& source, const std::vector<Eigen::Vector2d>& target);

}  // namespace slam2d
