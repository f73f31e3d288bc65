// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Stamp association of an estimated and a reference trajectory, the first step of the ATE and
// RPE metrics (Sturm et al. 2012, "A benchmark for the evaluation of RGB-D SLAM systems", IROS,
// Sec. VI): each estimate pose is paired with the reference pose nearest in time.

#include <cstddef>
#include <string>
#include <vector>

#include "slam2d/core/trajectory.hpp"

namespace slam2d {

/// An estimate pose and the reference pose matched to it.
struct AssociatedPose {
  double stamp = 0.0;               // s, the estimate's stamp
  std::size_t estimate_index = 0;   // into the estimate trajectory
  std::size_t reference_index = 0;  // into the reference trajectory
  SE2 T_estimate_robot;             // estimate pose, in the estimate's world frame
  SE2 T_reference_robot;            // reference pose, in the reference's world frame
};

/// Pairs every estimate pose with the reference pose whose stamp is nearest, if within
/// `stamp_tolerance` (s); unmatched estimate poses are dropped. The result is ordered by stamp
/// (stable), whatever the order of the inputs. A reference pose may be matched more than once
/// when the estimate is denser than the tolerance. Throws Error on a negative or non-finite
/// tolerance or on a non-finite stamp or pose in either trajectory.
std::vector<AssociatedPose> associate_by_stamp(const Trajectory& estimate, const Trajectory& reference,
                                               double stamp_tolerance);

/// Throws Error("<what>: pose N has a non-finite stamp or pose") unless every stamp and pose
/// coordinate is finite.
void check_finite_trajectory(const Trajectory& trajectory, const std::string& what);

/// Throws Error unless `tolerance` is finite and >= 0.
void check_stamp_tolerance(double tolerance, const std::string& what);

}  // namespace slam2d
