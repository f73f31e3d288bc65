// SPDX-License-Identifier: BSD-3-Clause
// Shared steps of the closest-point matchers; see nearest_association.hpp.

#include "slam2d/registration/nearest_association.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/degeneracy.hpp"

namespace slam2d {

void associate_closest(const KdTree2& tree, const std::vector<Point2>& source_points, const SE2& T_target_source,
                       double max_distance, std::vector<PointPair>& pairs) {
  const Eigen::Matrix2d R = T_target_source.rotation();
  const Point2& t = T_target_source.translation();
  const double max_squared = max_distance * max_distance;
  pairs.clear();
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    const Neighbor closest = tree.nearest(R * source_points[i] + t);
    if (closest.index < tree.size() && closest.squared_distance <= max_squared) {
      pairs.push_back({i, closest.index, closest.squared_distance});
    }
  }
}

void keep_pairs_with_normals(const PointCloud2& target, std::vector<PointPair>& pairs) {
  std::size_t kept = 0;
  for (const PointPair& pair : pairs) {
    if (has_normal(target, pair.target)) pairs[kept++] = pair;
  }
  pairs.resize(kept);
}

void keep_closest_pairs(std::vector<PointPair>& pairs, std::size_t kept, std::vector<double>& scratch) {
  const std::size_t n = pairs.size();
  if (kept >= n) return;
  if (kept == 0) {
    pairs.clear();
    return;
  }
  scratch.resize(n);
  for (std::size_t i = 0; i < n; ++i) scratch[i] = pairs[i].squared_distance;
  std::nth_element(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(kept - 1), scratch.end());
  const double cut = scratch[kept - 1];
  std::size_t below = 0;
  for (const PointPair& pair : pairs) below += pair.squared_distance < cut ? 1 : 0;
  std::size_t ties = kept - below;  // pairs exactly at the cut that still fit, first come first kept
  std::erase_if(pairs, [&](const PointPair& pair) {
    if (pair.squared_distance < cut) return false;
    if (pair.squared_distance == cut && ties > 0) {
      --ties;
      return false;
    }
    return true;
  });
}

void gather_pairs(const std::vector<PointPair>& pairs, const PointCloud2& target, const PointCloud2& source,
                  const SE2& T_target_source, std::vector<Point2>& target_points, std::vector<Point2>& source_points,
                  std::vector<Point2>* target_normals) {
  const Eigen::Matrix2d R = T_target_source.rotation();
  const Point2& t = T_target_source.translation();
  target_points.clear();
  source_points.clear();
  if (target_normals) target_normals->clear();
  for (const PointPair& pair : pairs) {
    target_points.push_back(target.points[pair.target]);
    source_points.push_back(R * source.points[pair.source] + t);
    if (target_normals) target_normals->push_back(target.normals[pair.target]);
  }
}

std::vector<Correspondence> to_correspondences(const std::vector<PointPair>& pairs) {
  std::vector<Correspondence> correspondences;
  correspondences.reserve(pairs.size());
  for (const PointPair& pair : pairs) correspondences.push_back({pair.source, pair.target, kNoPoint, 1.0});
  return correspondences;
}

PointCloud2 with_normals(const PointCloud2& target, const KdTree2& tree, const NormalEstimationConfig& config) {
  check(target.normals.empty() || target.normals.size() == target.size(),
        "matcher: the target cloud has normals, but not one per point");
  PointCloud2 copy = target;
  if (!copy.has_normals()) estimate_normals(copy, tree, config);
  return copy;
}

void finish_match(const PointCloud2& target, const PointCloud2& source,
                  const std::vector<Correspondence>& correspondences, ErrorMetric metric,
                  std::size_t min_correspondences, MatchResult& result, const SensorNoise& noise) {
  result.inliers = correspondences.size();
  result.residual = correspondences.empty()
                        ? 0.0
                        : rms_residual(target, source, result.T_target_source, correspondences, metric);
  if (correspondences.size() < min_correspondences) {
    result.covariance = MatchResult{}.covariance;
    result.degenerate = true;
    return;
  }
  result.covariance = censi_covariance(target, source, result.T_target_source, correspondences, metric, noise);
  apply(analyze_degeneracy(target, source, result.T_target_source, correspondences), result);
}

MatchResult unmatched(const SE2& T_target_source_guess, int iterations) {
  MatchResult result;
  result.T_target_source = T_target_source_guess;
  result.iterations = iterations;
  result.degenerate = true;
  return result;
}

bool step_below(const SE2& before, const SE2& after, double translation, double rotation) {
  return (after.translation() - before.translation()).norm() < translation &&
         std::abs(normalize_angle(after.theta() - before.theta())) < rotation;
}

PoseCycle::PoseCycle(std::size_t period) : period_(period) {
  check(period >= 1 && period <= kMaxPeriod, "PoseCycle: the period must lie in [1, 4]");
}

bool PoseCycle::returned_to(const SE2& pose, double translation, double rotation) {
  const std::size_t seen = std::min(count_, period_);
  const bool returned = std::any_of(recent_.begin(), recent_.begin() + static_cast<std::ptrdiff_t>(seen),
                                    [&](const SE2& before) { return step_below(before, pose, translation, rotation); });
  recent_[count_++ % period_] = pose;
  return returned;
}

}  // namespace slam2d
