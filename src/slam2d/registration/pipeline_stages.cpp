// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/pipeline_stages.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/closed_form.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"
#include "slam2d/registration/detail/pl_icp_search.hpp"

namespace slam2d {

ErrorMetric error_metric(Minimizer minimizer) {
  return minimizer == Minimizer::kPointToPoint ? ErrorMetric::kPointToPoint : ErrorMetric::kPointToLine;
}

TargetIndex::TargetIndex(const PointCloud2& target, const AssociationConfig& config) : config_(config) {
  if (config.kind == AssociationKind::kKdTree) {
    tree_ = std::make_unique<KdTree2>(target.points);
  } else {
    scan_ = std::make_unique<pl_icp_detail::TargetIndex>();  // in place: its kd-tree fallback indexes its points
    pl_icp_detail::prepare_target(target, PlIcpSearch::kProjective, *scan_);
  }
}

TargetIndex::~TargetIndex() = default;

void TargetIndex::associate(const std::vector<Point2>& source_points, const SE2& T_target_source,
                            std::vector<PointPair>& pairs) const {
  if (tree_) {
    associate_closest(*tree_, source_points, T_target_source, config_.max_distance, pairs);  // the matchers' own
    return;
  }
  // Censi 2008, Sec. IV-B, PL-ICP's search (pl_icp_search.hpp): exact, closest strictly within
  // max_distance; each walk starts at the point's previous match or its neighbour's.
  pairs.clear();
  tracked_.resize(source_points.size());
  const Eigen::Matrix2d R = T_target_source.rotation();
  const Point2& t = T_target_source.translation();
  int previous = pl_icp_detail::kNone;
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    const Point2 moved = R * source_points[i] + t;
    const int j = pl_icp_detail::track_nearest(*scan_, moved, config_.max_distance, tracked_[i], previous);
    if (j == pl_icp_detail::kNone) continue;
    previous = j;
    pairs.push_back({i, scan_->original[static_cast<std::size_t>(j)], (scan_->points[j] - moved).squaredNorm()});
  }
}

namespace {

// Besl & McKay 1992, Sec. III-C: the exact minimiser of sum |T m_i - q_i|^2 over rigid motions
// (closed_form.hpp, by SVD: the same as the quaternion to rounding).
std::optional<MinimizerStep> point_to_point_step(const PointCloud2& target, const PointCloud2& source, const SE2& T,
                                                 const std::vector<PointPair>& pairs, PairedPoints& paired) {
  if (pairs.size() < 2) return std::nullopt;
  gather_pairs(pairs, target, source, T, paired.target, paired.source);
  double error = 0.0;
  for (const PointPair& pair : pairs) error += pair.squared_distance;
  const SE2 step = solve_point_to_point_svd(paired.target, paired.source);
  return MinimizerStep{step, error / static_cast<double>(pairs.size())};
}

// Low 2004, Sec. 2, in the plane: with R(theta) m ~ m + theta J m the residual n^T (R m + t - q)
// is linear in (theta, t_x, t_y); the least-squares step by the pseudo-inverse (closed_form.hpp),
// the same solve as match_point_to_plane's.
std::optional<MinimizerStep> point_to_line_step(const PointCloud2& target, const PointCloud2& source, const SE2& T,
                                                const std::vector<PointPair>& pairs, PairedPoints& paired) {
  if (pairs.size() < 3) return std::nullopt;
  gather_pairs(pairs, target, source, T, paired.target, paired.source, &paired.normals);
  double error = 0.0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const double residual = paired.normals[k].dot(paired.source[k] - paired.target[k]);
    error += residual * residual;
  }
  const auto step = solve_point_to_plane(paired.target, paired.normals, paired.source);
  if (!step) return std::nullopt;
  return MinimizerStep{*step, error / static_cast<double>(pairs.size())};
}

}  // namespace

std::optional<MinimizerStep> minimize_step(Minimizer minimizer, const PointCloud2& target, const PointCloud2& source,
                                           const SE2& T_target_source, const std::vector<PointPair>& pairs,
                                           PairedPoints& paired) {
  return minimizer == Minimizer::kPointToPoint ? point_to_point_step(target, source, T_target_source, pairs, paired)
                                               : point_to_line_step(target, source, T_target_source, pairs, paired);
}

}  // namespace slam2d
