// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/eval/ate.hpp"

#include <cmath>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/eval/detail/association.hpp"
#include "slam2d/eval/statistics.hpp"

namespace slam2d {

namespace {

Eigen::Vector2d centroid(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const auto& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

}  // namespace

SE2 align_rigid_2d(const std::vector<Eigen::Vector2d>& source, const std::vector<Eigen::Vector2d>& target) {
  check(!source.empty(), "align_rigid_2d: no points");
  check(source.size() == target.size(), "align_rigid_2d: source and target sizes differ");
  // Umeyama Eq. (34)-(35): centroids; Eq. (38)-(39): cross-covariance of the centred points.
  const Eigen::Vector2d mean_source = centroid(source);
  const Eigen::Vector2d mean_target = centroid(target);
  double dot_sum = 0.0;
  double cross_sum = 0.0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector2d s = source[i] - mean_source;
    const Eigen::Vector2d t = target[i] - mean_target;
    dot_sum += s.dot(t);
    cross_sum += s.x() * t.y() - s.y() * t.x();
  }
  // Eq. (40) in 2D: the rotation maximising sum t_i . R s_i; Eq. (41): the translation.
  const double theta = (dot_sum == 0.0 && cross_sum == 0.0) ? 0.0 : std::atan2(cross_sum, dot_sum);
  const SE2 rotation(0.0, 0.0, theta);
  return SE2(mean_target - rotation.rotation() * mean_source, theta);
}

AteResult absolute_trajectory_error(const Trajectory& estimate, const Trajectory& reference, const AteConfig& config) {
  const std::vector<AssociatedPose> pairs = associate_by_stamp(estimate, reference, config.stamp_tolerance);
  check(pairs.size() >= 2, "absolute_trajectory_error: only " + std::to_string(pairs.size()) +
                               " estimate poses have a reference pose within " +
                               std::to_string(config.stamp_tolerance) +
                               " s (need at least 2); check the time bases and the stamp tolerance");
  std::vector<Eigen::Vector2d> source;
  std::vector<Eigen::Vector2d> target;
  source.reserve(pairs.size());
  target.reserve(pairs.size());
  for (const AssociatedPose& pair : pairs) {
    source.push_back(pair.T_estimate_robot.translation());
    target.push_back(pair.T_reference_robot.translation());
  }
  AteResult result;
  result.matched = pairs.size();
  result.T_reference_estimate = align_rigid_2d(source, target);
  result.errors.reserve(pairs.size());
  result.estimate_indices.reserve(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    result.errors.push_back((result.T_reference_estimate * source[i] - target[i]).norm());
    result.estimate_indices.push_back(pairs[i].estimate_index);
  }
  result.rmse = root_mean_square(result.errors);
  const ErrorStatistics statistics = compute_statistics(result.errors);
  result.mean = statistics.mean;
  result.median = median(result.errors);
  result.max = statistics.max;
  return result;
}

}  // namespace slam2d
