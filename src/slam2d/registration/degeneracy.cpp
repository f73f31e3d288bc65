// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/degeneracy.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

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

// The sum of a_i a_i^T / sigma^2, a_i = (n, n^T J p), over points p (the source's, rotated into the
// target frame: |p| is the distance from the sensor) seen against surfaces with normal n.
class FisherInformation {
 public:
  explicit FisherInformation(const DegeneracyConfig& config)
      : config_(config), inverse_variance_(1.0 / (config.range_sigma * config.range_sigma)) {
    check(config.range_sigma > 0.0, "degeneracy: range_sigma must be > 0");
  }
  void add(const Point2& normal, const Point2& point) {
    const Eigen::Vector3d a(normal.x(), normal.y(), normal.dot(perpendicular(point)));
    information_ += inverse_variance_ * a * a.transpose();
    squared_radius_sum_ += point.squaredNorm();
    ++used_;
  }
  const Eigen::Matrix3d& matrix() const { return information_; }
  // With fewer than 3 points: degenerate, the weak direction x.
  DegeneracyAnalysis analysis() const {
    if (used_ < 3) {
      DegeneracyAnalysis analysis;
      analysis.information = information_;
      analysis.weak_direction = Eigen::Vector3d::UnitX();
      return analysis;
    }
    return analyze_information(information_, std::sqrt(squared_radius_sum_ / static_cast<double>(used_)), config_);
  }

 private:
  DegeneracyConfig config_;
  double inverse_variance_;
  Eigen::Matrix3d information_ = Eigen::Matrix3d::Zero();
  double squared_radius_sum_ = 0.0;
  std::size_t used_ = 0;
};

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
  const PointCloud2* with_normals = &target;
  PointCloud2 estimated;
  if (target.normals.size() != target.size() && needs_target_normals(correspondences)) {
    estimated.points = target.points;
    estimate_normals(estimated);
    with_normals = &estimated;
  }
  FisherInformation information(config);
  for (const Correspondence& c : correspondences) {
    if (c.source >= source.size() || !(c.weight > 0.0)) continue;
    const std::optional<Point2> n = normal_of(*with_normals, c);
    if (n) information.add(*n, T_target_source.rotation() * source.points[c.source]);
  }
  return information.analysis();
}

ScanGeometry scan_geometry(const std::vector<Eigen::Vector2d>& points_in_beam_order, const DegeneracyConfig& config) {
  constexpr std::size_t kReach = 4;          // beams either side of a point in its chord
  constexpr double kMaxGap = 0.5;            // m, as registration/normals.hpp's max_neighbor_distance
  constexpr std::size_t kMinSurface = 3;     // points in a surface (fewer: lone returns)
  constexpr std::size_t kEdgeLonePoints = 8;  // lone returns an edge may hide behind (mixed pixels)
  const std::vector<Eigen::Vector2d>& p = points_in_beam_order;
  // The surfaces: maximal runs of points joined by gaps under kMaxGap, [first, last].
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (runs.empty() || (p[i] - p[i - 1]).squaredNorm() > kMaxGap * kMaxGap) runs.emplace_back(i, i);
    runs.back().second = i;
  }
  const auto surface = [&](const std::pair<std::size_t, std::size_t>& run) { return run.second - run.first + 1 >= kMinSurface; };
  ScanGeometry geometry;
  geometry.returns = p.size();
  FisherInformation information(config);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const auto [first, last] = runs[r];
    if (!surface(runs[r])) {
      geometry.lone_returns += last - first + 1;
      continue;
    }
    // Each point against the chord through its neighbours up to kReach beams either side (a
    // total least squares fit over them gives nearly the same line and costs ten times as much).
    for (std::size_t i = first; i <= last; ++i) {
      const Eigen::Vector2d chord = p[std::min(last, i + kReach)] - p[std::max(first, i >= kReach ? i - kReach : 0)];
      const double length = chord.norm();
      if (length > 1e-9) information.add(perpendicular(chord) / length, p[i]);
    }
    // A depth edge: the next surface, behind at most kEdgeLonePoints lone returns, does not go on
    // along this one's line (a grazing wall sampled farther apart than kMaxGap does).
    for (std::size_t next = r + 1; next < runs.size() && runs[next].first - last - 1 <= kEdgeLonePoints; ++next) {
      if (!surface(runs[next])) continue;
      const Eigen::Vector2d along = (p[last] - p[std::max(first, last >= kReach ? last - kReach : 0)]).normalized();
      const Eigen::Vector2d step = p[runs[next].first] - p[last];
      if (!continues_line(along, step)) ++geometry.edges;
      break;
    }
  }
  geometry.information = information.matrix();
  return geometry;
}

std::optional<Eigen::Vector2d> open_translation(const ScanGeometry& geometry, double ratio) {
  constexpr double kMaxLoneShare = 0.25;  // of the returns (the header)
  const Eigen::Matrix3d& information = geometry.information;
  if (geometry.edges > 0 || !(information(2, 2) > 0.0)) return std::nullopt;
  if (static_cast<double>(geometry.lone_returns) > kMaxLoneShare * static_cast<double>(geometry.returns)) return std::nullopt;
  const Eigen::Matrix2d t =
      information.topLeftCorner<2, 2>() - information.block<2, 1>(0, 2) * information.block<1, 2>(2, 0) / information(2, 2);
  // The eigenvalues of the symmetric 2 x 2 matrix in closed form, and the weak one's eigenvector.
  const double mean = 0.5 * (t(0, 0) + t(1, 1));
  const double spread = std::hypot(0.5 * (t(0, 0) - t(1, 1)), t(0, 1));
  const double strong = mean + spread;
  const double weak = mean - spread;
  if (!(strong > 0.0) || weak >= ratio * strong) return std::nullopt;
  // The strong axis is at angle atan2(2 t01, t00 - t11) / 2; the weak one is perpendicular.
  const double angle = 0.5 * std::atan2(2.0 * t(0, 1), t(0, 0) - t(1, 1));
  return Eigen::Vector2d(-std::sin(angle), std::cos(angle));
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
