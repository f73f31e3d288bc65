// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/degeneracy.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {
namespace {

Point2 perpendicular(const Point2& v) { return {-v.y(), v.x()}; }

bool needs_target_normals(const std::vector<Correspondence>& correspondences) {
  for (const Correspondence& c : correspondences) {
    if (c.target2 == kNoPoint) return true;
  }
  return false;
}

// The target surface normal a correspondence sees, if it has one.
std::optional<Point2> normal_of(const PointCloud2& target, const Correspondence& c) {
  if (c.target >= target.size()) return std::nullopt;
  if (c.target2 != kNoPoint) {
    if (c.target2 >= target.size()) return std::nullopt;
    const Point2 d = target.points[c.target2] - target.points[c.target];
    const double length = d.norm();
    if (!(length > 1e-12)) return std::nullopt;
    return Point2(perpendicular(d) / length);
  }
  if (!has_normal(target, c.target)) return std::nullopt;
  return target.normals[c.target];
}

}  // namespace

DegeneracyAnalysis analyze_information(const Eigen::Matrix3d& information, double length_scale,
                                       const DegeneracyConfig& config) {
  check(config.min_eigenvalue_ratio >= 0.0 && config.min_eigenvalue_ratio <= 1.0,
        "degeneracy: min_eigenvalue_ratio must be in [0, 1]");
  DegeneracyAnalysis analysis;
  analysis.information = information;
  analysis.length_scale = length_scale > 1e-9 ? length_scale : 1.0;
  // Rotation as arc length at L: theta' = L theta, so I' = S I S with S = diag(1, 1, 1 / L).
  const Eigen::Vector3d s(1.0, 1.0, 1.0 / analysis.length_scale);
  const Eigen::Matrix3d scaled = s.asDiagonal() * information * s.asDiagonal();
  if (!scaled.allFinite()) return analysis;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(0.5 * (scaled + scaled.transpose()));
  analysis.eigenvalues = solver.eigenvalues();  // ascending
  for (int k = 0; k < 3; ++k) {
    // Back from (x, y, theta') to (x, y, theta): theta = theta' / L.
    Eigen::Vector3d direction = solver.eigenvectors().col(k);
    direction.z() /= analysis.length_scale;
    analysis.directions.col(k) = direction.normalized();
  }
  const double largest = analysis.eigenvalues.z();
  analysis.degenerate = !(largest > 0.0) || analysis.eigenvalues.x() < config.min_eigenvalue_ratio * largest;
  analysis.weak_direction = analysis.directions.col(0);
  return analysis;
}

DegeneracyAnalysis analyze_degeneracy(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                                      const std::vector<Correspondence>& correspondences,
                                      const DegeneracyConfig& config) {
  check(config.range_sigma > 0.0, "degeneracy: range_sigma must be > 0");
  const PointCloud2* with_normals = &target;
  PointCloud2 estimated;
  if (target.normals.size() != target.size() && needs_target_normals(correspondences)) {
    estimated.points = target.points;
    estimate_normals(estimated);
    with_normals = &estimated;
  }
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  double squared_radius_sum = 0.0;
  std::size_t used = 0;
  const double inverse_variance = 1.0 / (config.range_sigma * config.range_sigma);
  for (const Correspondence& c : correspondences) {
    if (c.source >= source.size() || !(c.weight > 0.0)) continue;
    const std::optional<Point2> n = normal_of(*with_normals, c);
    if (!n) continue;
    const Point2 Rp = T_target_source.rotation() * source.points[c.source];
    const Eigen::Vector3d a(n->x(), n->y(), n->dot(perpendicular(Rp)));
    information += inverse_variance * a * a.transpose();
    squared_radius_sum += source.points[c.source].squaredNorm();
    ++used;
  }
  if (used < 3) {
    DegeneracyAnalysis analysis;
    analysis.information = information;
    analysis.weak_direction = Eigen::Vector3d::UnitX();
    return analysis;
  }
  return analyze_information(information, std::sqrt(squared_radius_sum / static_cast<double>(used)), config);
}

void apply(const DegeneracyAnalysis& analysis, MatchResult& result) {
  result.degenerate = analysis.degenerate;
  result.weak_direction = analysis.weak_direction;
  result.information_eigenvalues = analysis.eigenvalues;
  if (!analysis.degenerate) return;
  // A closed-form covariance from sampled walls pins even an unobservable direction a little
  // (noisy normals lend it information). Along the weak direction w the variance is raised to at
  // least the Cramer-Rao bound 1 / (w^T I w) and at least the variance along the strongest
  // direction times the information's eigenvalue ratio, the shape I^-1 would have.
  const Eigen::Vector3d& w = analysis.weak_direction;
  const Eigen::Vector3d strongest = analysis.directions.col(2);
  const double weak_information = w.dot(analysis.information * w);
  double bound = weak_information > 1.0 / kUnknownVariance ? 1.0 / weak_information : kUnknownVariance;
  if (analysis.eigenvalues.x() > 0.0) {
    const double ratio = analysis.eigenvalues.z() / analysis.eigenvalues.x();
    bound = std::max(bound, ratio * strongest.dot(result.covariance * strongest));
  } else {
    bound = kUnknownVariance;
  }
  bound = std::min(bound, kUnknownVariance);
  const double current = w.dot(result.covariance * w);
  if (bound > current) result.covariance += (bound - current) * w * w.transpose();
}

}  // namespace slam2d
