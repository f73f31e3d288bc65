// SPDX-License-Identifier: BSD-3-Clause
// Point-to-plane ICP by linear least squares: K.-L. Low, TR04-004, UNC Chapel Hill, 2004, in 2D.
// See point_to_plane.hpp; the linear system is solve_point_to_plane (closed_form.cpp).

#include "slam2d/registration/point_to_plane.hpp"

#include <optional>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/closed_form.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {
namespace {

constexpr std::size_t kMinPoints = 3;

struct PointToPlaneBuffers {
  std::vector<PointPair> pairs;
  std::vector<Point2> target_points;
  std::vector<Point2> target_normals;
  std::vector<Point2> source_points;  // moved by the current estimate
};

// Closest points at T, far pairs and targets without a normal left out.
void associate(const KdTree2& tree, const PointCloud2& model, const PointCloud2& source, const SE2& T,
               const PointToPlaneConfig& config, std::vector<PointPair>& pairs) {
  associate_closest(tree, source.points, T, config.max_correspondence_distance, pairs);
  keep_pairs_with_normals(model, pairs);
}

}  // namespace

void validate(const PointToPlaneConfig& config) {
  check_fields(config, "PointToPlaneConfig");
}

MatchResult match_point_to_plane(const PointCloud2& target, const PointCloud2& source,
                                 const SE2& T_target_source_guess, const PointToPlaneConfig& config) {
  validate(config);
  if (target.size() < kMinPoints || source.size() < kMinPoints) return unmatched(T_target_source_guess);
  const KdTree2 tree(target.points);
  return match_point_to_plane(tree, target, source, T_target_source_guess, config);
}

MatchResult match_point_to_plane(const KdTree2& tree, const PointCloud2& target, const PointCloud2& source,
                                 const SE2& T_target_source_guess, const PointToPlaneConfig& config) {
  validate(config);
  if (target.size() < kMinPoints || source.size() < kMinPoints) return unmatched(T_target_source_guess);
  check(tree.size() == target.size(), "point-to-plane: the kd-tree is not over the target's points");
  const PointCloud2 model = with_normals(
      target, tree,
      {config.normal_neighbors, config.normal_max_distance, config.normal_min_neighbors});  // the d_i with n_i
  const auto min_pairs = static_cast<std::size_t>(config.min_correspondences);
  PointToPlaneBuffers buffers;
  MatchResult result;
  SE2 T = T_target_source_guess;
  PoseCycle cycle;
  for (int k = 0; k < config.max_iterations; ++k) {
    associate(tree, model, source, T, config, buffers.pairs);
    if (buffers.pairs.size() < min_pairs) break;
    gather_pairs(buffers.pairs, model, source, T, buffers.target_points, buffers.source_points,
                 &buffers.target_normals);
    // Low Eq. (1) linearised: argmin sum ((M s_i - d_i) . n_i)^2, solved as A x = b.
    const std::optional<SE2> increment =
        solve_point_to_plane(buffers.target_points, buffers.target_normals, buffers.source_points);
    if (!increment) break;
    T = *increment * T;
    result.iterations = k + 1;
    if (step_below(SE2(), *increment, config.min_translation_step, config.min_rotation_step) ||
        cycle.returned_to(T, config.min_translation_step, config.min_rotation_step)) {
      result.converged = true;
      break;
    }
  }
  // The final correspondences at the estimate: point-to-line along the target normals.
  result.T_target_source = T;
  associate(tree, model, source, T, config, buffers.pairs);
  if (buffers.pairs.size() < min_pairs) result.converged = false;
  finish_match(model, source, to_correspondences(buffers.pairs), ErrorMetric::kPointToLine, min_pairs, result);
  return result;
}

}  // namespace slam2d
