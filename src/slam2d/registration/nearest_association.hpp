// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The steps the closest-point matchers share (icp.cpp, trimmed_icp.cpp, point_to_plane.cpp, and
// the stages of the modular pipeline, pipeline_stages.cpp and pipeline.cpp):
// closest-point association by kd-tree with distance rejection (Besl & McKay 1992, Sec. III-A:
// y = C(p, X), the closest model point), gathering the pairs for a closed-form solver
// (closed_form.hpp), and filling a MatchResult from the final correspondences.
// Internal to the registration module: buffers are the caller's, reused across iterations.

#include <array>
#include <cstddef>
#include <vector>

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/match_result.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {

/// A source point and its closest target point.
struct PointPair {
  std::size_t source = 0;
  std::size_t target = 0;
  double squared_distance = 0.0;  // m^2, |T p - q|^2 when associated
};

/// Pairs every source point, moved by T_target_source, with its closest target point in `tree`;
/// pairs farther apart than `max_distance` (m; infinity keeps all) are left out. Refills `pairs`.
void associate_closest(const KdTree2& tree, const std::vector<Point2>& source_points, const SE2& T_target_source,
                       double max_distance, std::vector<PointPair>& pairs);

/// Keeps the pairs whose target point has a normal (has_normal), in order.
void keep_pairs_with_normals(const PointCloud2& target, std::vector<PointPair>& pairs);

/// Least trimmed squares (D. Chetverikov et al., "The trimmed iterative closest point algorithm",
/// ICPR 2002, Sec. 3, step 2): keeps the `kept` pairs with the smallest squared distances, in
/// their order; ties at the cut are kept first come first (the whole list when kept >= its
/// size). `scratch` is the caller's buffer (no allocation once it has grown). Trimmed ICP and
/// the pipeline's trimmed filter.
void keep_closest_pairs(std::vector<PointPair>& pairs, std::size_t kept, std::vector<double>& scratch);

/// The paired points into the caller's buffers: target_points[i] = target[pairs[i].target] and
/// source_points[i] = T_target_source * source[pairs[i].source]; target_normals too when given.
void gather_pairs(const std::vector<PointPair>& pairs, const PointCloud2& target, const PointCloud2& source,
                  const SE2& T_target_source, std::vector<Point2>& target_points, std::vector<Point2>& source_points,
                  std::vector<Point2>* target_normals = nullptr);

/// The pairs as point-to-point correspondences, or point-to-line ones along the target's normal
/// (target2 = kNoPoint).
std::vector<Correspondence> to_correspondences(const std::vector<PointPair>& pairs);

/// The target with normals: a copy, with estimate_normals over `tree` (which indexes
/// target.points) when the target has none. Error if it has normals but not one per point.
PointCloud2 with_normals(const PointCloud2& target, const KdTree2& tree, const NormalEstimationConfig& config = {});

/// Fills inliers, residual (rms_residual), covariance (censi_covariance under `metric`) and the
/// degeneracy verdict at result.T_target_source. With fewer than `min_correspondences` pairs the
/// covariance stays huge and the match is flagged degenerate. `target` must carry normals.
void finish_match(const PointCloud2& target, const PointCloud2& source,
                  const std::vector<Correspondence>& correspondences, ErrorMetric metric,
                  std::size_t min_correspondences, MatchResult& result, const SensorNoise& noise = {});

/// The result of a match that could not start (too few points) or failed after `iterations`:
/// the guess, not converged, huge covariance, degenerate.
MatchResult unmatched(const SE2& T_target_source_guess, int iterations = 0);

/// True when `after` differs from `before` by less than `translation` (m) and `rotation` (rad).
bool step_below(const SE2& before, const SE2& after, double translation, double rotation);

/// The iteration's poses of the last few steps: an iteration that comes back to one of them has
/// entered a cycle of the associations (the pairs alternate between sets, so the steps never
/// shrink below the stopping test), and is at its end, as CSM's loop detection has it. The one
/// home of that test for the matchers that iterate on poses: point-to-plane remembers four poses,
/// IDC, IMRP and the tangent search two (their papers' alternation between two sets). PL-ICP
/// detects the same on its association sets (pl_icp.cpp).
class PoseCycle {
 public:
  static constexpr std::size_t kMaxPeriod = 4;  // the longest cycle recognised, in iterations

  /// Throws Error unless 1 <= period <= kMaxPeriod.
  explicit PoseCycle(std::size_t period = kMaxPeriod);

  /// True when `pose` lies within `translation` and `rotation` of one of the last `period` poses
  /// given (step_below); `pose` is then remembered.
  bool returned_to(const SE2& pose, double translation, double rotation);

 private:
  std::array<SE2, kMaxPeriod> recent_{};
  std::size_t period_;
  std::size_t count_ = 0;
};

}  // namespace slam2d
