// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/eval/rpe.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/eval/detail/association.hpp"
#include "slam2d/eval/statistics.hpp"

namespace slam2d {

namespace {

// Position of each associated pose along the window axis: stamp, or cumulative path length of the
// reference. Both never decrease, since the pairs are ordered by stamp.
std::vector<double> positions_along(const std::vector<AssociatedPose>& pairs, RpeWindow window) {
  std::vector<double> along(pairs.size(), 0.0);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (window == RpeWindow::kTime) {
      along[i] = pairs[i].stamp;
    } else if (i > 0) {
      const Eigen::Vector2d step =
          pairs[i].T_reference_robot.translation() - pairs[i - 1].T_reference_robot.translation();
      along[i] = along[i - 1] + step.norm();
    }
  }
  return along;
}

// Sturm et al. Eq. (1): E_ij = (Ref_i^-1 Ref_j)^-1 (Est_i^-1 Est_j).
SE2 relative_error(const AssociatedPose& i, const AssociatedPose& j) {
  const SE2 reference_motion = i.T_reference_robot.between(j.T_reference_robot);
  const SE2 estimate_motion = i.T_estimate_robot.between(j.T_estimate_robot);
  return reference_motion.between(estimate_motion);
}

RpeStatistics summarise(std::span<const double> values) {
  const ErrorStatistics statistics = compute_statistics(values);
  return {root_mean_square(values), statistics.mean, statistics.max};
}

}  // namespace

RpeResult relative_pose_error(const Trajectory& estimate, const Trajectory& reference, const RpeConfig& config) {
  check_fields(config, "RpeConfig");
  const std::vector<AssociatedPose> pairs = associate_by_stamp(estimate, reference, config.stamp_tolerance);
  const std::vector<double> along = positions_along(pairs, config.window);
  RpeResult result;
  std::vector<double> translation;
  std::vector<double> rotation_deg;
  // Eq. (2) over every i: j is the first pose with along[j] - along[i] >= delta. Since `along`
  // never decreases, j never moves back as i advances.
  std::size_t j = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < pairs.size() && along[j] - along[i] < config.delta) ++j;
    if (j == pairs.size()) break;
    const SE2 error = relative_error(pairs[i], pairs[j]);
    translation.push_back(error.translation().norm());
    rotation_deg.push_back(rad_to_deg(std::abs(error.theta())));
    result.errors.push_back({pairs[i].stamp, pairs[j].stamp, translation.back(), rotation_deg.back()});
  }
  result.matched = pairs.size();
  result.pairs = translation.size();
  result.translation = summarise(translation);
  result.rotation_deg = summarise(rotation_deg);
  return result;
}

}  // namespace slam2d
