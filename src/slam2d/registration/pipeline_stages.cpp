#include "slam2d/registration/pipeline_stages.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/closed_form.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {

ErrorMetric error_metric(Minimizer minimizer) {
  return minimizer == Minimizer::kPointToPoint ? ErrorMetric::kPointToPoint : ErrorMetric::kPointToLine;
}

double pseudo_bearing(const Point2& p) {
  const double x = p.x();
  const double y = p.y();
  const double sum = std::abs(x) + std::abs(y);
  if (!(sum > 0.0)) return 0.0;
  if (y >= 0.0) return x >= 0.0 ? y / sum : 1.0 - x / sum;  // [0, 1) first quadrant, [1, 2) second
  return x < 0.0 ? 2.0 - y / sum : 3.0 + x / sum;           // [2, 3) third, [3, 4) fourth
}

TargetIndex::TargetIndex(const PointCloud2& target, const AssociationConfig& config)
    : target_(&target), config_(config) {
  if (config.kind == AssociationKind::kKdTree) {
    tree_ = std::make_unique<KdTree2>(target.points);
    return;
  }
  order_.resize(target.size());
  std::iota(order_.begin(), order_.end(), std::size_t{0});
  std::vector<double> bearing(target.size());
  for (std::size_t j = 0; j < target.size(); ++j) bearing[j] = pseudo_bearing(target.points[j]);
  std::stable_sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) { return bearing[a] < bearing[b]; });
  bearings_.resize(target.size());
  for (std::size_t k = 0; k < order_.size(); ++k) bearings_[k] = bearing[order_[k]];
}

TargetIndex::~TargetIndex() = default;

// Censi 2008, Sec. IV-B: the source point's bearing in the target scan names a place in the
// target's bearing order; the closest target point within +-window places of it wins. The
// order is circular (modulo n), so a 360 degree scan has no seam.
std::size_t TargetIndex::closest_projective(const Point2& query, double& squared_distance) const {
  const std::size_t n = bearings_.size();
  const auto place = static_cast<std::ptrdiff_t>(
      std::lower_bound(bearings_.begin(), bearings_.end(), pseudo_bearing(query)) - bearings_.begin());
  const auto window = static_cast<std::ptrdiff_t>(config_.window);
  const auto count = static_cast<std::ptrdiff_t>(n);
  std::size_t best = n;
  squared_distance = std::numeric_limits<double>::infinity();
  // The bearing lies between places `place - 1` and `place`: window more on either side.
  for (std::ptrdiff_t offset = -window - 1; offset <= window; ++offset) {
    const std::size_t j = order_[static_cast<std::size_t>(((place + offset) % count + count) % count)];
    const double d2 = (target_->points[j] - query).squaredNorm();
    if (d2 < squared_distance) {
      squared_distance = d2;
      best = j;
    }
  }
  return best;
}

void TargetIndex::associate(const std::vector<Point2>& source_points, const SE2& T_target_source,
                            std::vector<PointPair>& pairs) const {
  if (tree_) {
    associate_closest(*tree_, source_points, T_target_source, config_.max_distance, pairs);  // the matchers' own
    return;
  }
  pairs.clear();
  if (target_->empty()) return;
  const Eigen::Matrix2d R = T_target_source.rotation();
  const Point2& t = T_target_source.translation();
  const double max2 = config_.max_distance * config_.max_distance;
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    double d2 = 0.0;
    const std::size_t j = closest_projective(R * source_points[i] + t, d2);
    if (d2 <= max2) pairs.push_back({i, j, d2});
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
