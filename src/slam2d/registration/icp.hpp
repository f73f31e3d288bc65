// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Point-to-point ICP: P. J. Besl and N. D. McKay, "A method for registration of 3-D shapes",
// IEEE PAMI 14(2), 1992, in the plane. Each iteration pairs every source point, moved by the
// current estimate, with its closest target point (kd-tree, Sec. III-A), rejects pairs farther
// apart than `max_correspondence_distance` (not in the paper, which assumes the data to be a
// subset of the model), and registers the original source points to their closest points in
// closed form (Sec. III-C: SVD or unit quaternion, closed_form.hpp). `accelerated` adds the
// paper's accelerated ICP (Sec. IV-C): when the last two steps of the registration vector point
// the same way (within `acceleration_angle`), the vector is moved on along the step to the zero
// of a line or the minimum of a parabola fitted to the last three errors, at most
// `acceleration_max_factor` times the step; an extrapolation whose closest-point error exceeds
// the error plain ICP had reached is undone (a guard of ours, see icp.cpp).
//
// Presets: configs/icp.yaml, configs/icp-accelerated.yaml. Method page: docs/methods/icp.md.

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/closed_form.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct IcpConfig {
  int max_iterations = 50;                  // 1, >= 1; registrations before giving up
  double max_correspondence_distance = 1.0;  // m, > 0; pairs farther apart are rejected
  int min_correspondences = 10;             // 1, >= 3; fewer pairs and the match fails
  PointToPointSolver solver = PointToPointSolver::kSvd;  // kSvd | kQuaternion (same answer)
  double min_mse_change = 1e-8;             // m^2, >= 0; stop when |d_{k-1} - d_k| falls below (Besl's tau)
  double min_translation_step = 1e-4;       // m, >= 0; stop when a step moves less than this ...
  double min_rotation_step = 1e-4;          // rad, >= 0; ... and turns less than this
  bool accelerated = false;                 // Besl & McKay's accelerated ICP (Sec. IV-C)
  double acceleration_angle = 0.1745329252;  // rad, in (0, pi); steps within this angle are aligned (paper: 10 deg)
  double acceleration_max_factor = 25.0;    // 1, > 0; extrapolation capped at this times the last step (paper: 25)
};

template <typename Fields>
void describe(Fields& f, IcpConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "registrations before giving up");
  f.number("max_correspondence_distance", c.max_correspondence_distance, "m", greater_than(0), "pairs farther apart are rejected");
  f.number("min_correspondences", c.min_correspondences, "1", at_least(3), "fewer pairs and the match fails");
  f.choice("solver", c.solver, "closed-form registration (same answer)");
  f.number("min_mse_change", c.min_mse_change, "m^2", at_least(0), "stop when the MSE changes by less (Besl's tau)");
  f.number("min_translation_step", c.min_translation_step, "m", at_least(0), "stop when a step moves less than this ...");
  f.number("min_rotation_step", c.min_rotation_step, "rad", at_least(0), "... and turns less than this");
  f.flag("accelerated", c.accelerated, "Besl & McKay's accelerated ICP (Sec. IV-C)");
  f.number("acceleration_angle", c.acceleration_angle, "rad", open_interval(0, 3.141592653589793),
           "steps within this angle are aligned (paper: 10 deg)");
  f.number("acceleration_max_factor", c.acceleration_max_factor, "1", greater_than(0),
           "extrapolation capped at this times the last step (paper: 25)");
}

/// Throws Error when a field is out of its range.
void validate(const IcpConfig& config);

/// Registers `source` to `target` (both in their sensor frames) from the guess. The covariance
/// is Censi's closed form for the point-to-point metric at the final closest-point pairs;
/// `iterations` counts registrations; `converged` is true when the MSE-change or step test
/// stopped the loop. Fewer than 3 points in either cloud: the guess, not converged.
MatchResult match_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                      const IcpConfig& config = {});

}  // namespace slam2d
