// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/eval/detail/association.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

void check_finite_trajectory(const Trajectory& trajectory, const std::string& what) {
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const StampedPose& p = trajectory[i];
    const bool finite = std::isfinite(p.stamp) && p.pose.vector().allFinite();
    check(finite, what + ": pose " + std::to_string(i) + " has a non-finite stamp or pose");
  }
}

void check_stamp_tolerance(double tolerance, const std::string& what) {
  check(std::isfinite(tolerance) && tolerance >= 0.0,
        what + ": stamp_tolerance must be finite and >= 0 s, got " + std::to_string(tolerance));
}

std::vector<AssociatedPose> associate_by_stamp(const Trajectory& estimate, const Trajectory& reference,
                                               double stamp_tolerance) {
  check_stamp_tolerance(stamp_tolerance, "associate_by_stamp");
  check_finite_trajectory(estimate, "associate_by_stamp: estimate");
  check_finite_trajectory(reference, "associate_by_stamp: reference");
  const StampIndex index(reference);
  std::vector<AssociatedPose> pairs;
  pairs.reserve(estimate.size());
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    const auto j = index.nearest(estimate[i].stamp, stamp_tolerance);
    if (!j) continue;
    pairs.push_back({estimate[i].stamp, i, *j, estimate[i].pose, reference[*j].pose});
  }
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const AssociatedPose& a, const AssociatedPose& b) { return a.stamp < b.stamp; });
  return pairs;
}

}  // namespace slam2d
