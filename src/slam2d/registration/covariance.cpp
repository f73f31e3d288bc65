// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/covariance.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <optional>

namespace slam2d {
namespace {

Eigen::Matrix2d rotation(double theta) {
  Eigen::Matrix2d R;
  R << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta);
  return R;
}

Point2 perpendicular(const Point2& v) { return {-v.y(), v.x()}; }

// One correspondence with its measurements copied out, so that they can be perturbed: the source
// point p, the target point q1 and, for a segment, its second end q2 (else the fixed normal).
struct Term {
  Point2 p = Point2::Zero();
  Point2 q1 = Point2::Zero();
  Point2 q2 = Point2::Zero();
  Point2 fixed_normal = Point2::Zero();
  bool segment = false;
  double weight = 1.0;

  // The unit normal of the target line (zero for a degenerate segment).
  Point2 normal() const {
    if (!segment) return fixed_normal;
    const Point2 d = q2 - q1;
    const double length = d.norm();
    return length > 1e-12 ? Point2(perpendicular(d) / length) : Point2::Zero();
  }
};

// The residual and its Jacobian with respect to x = (t_x, t_y, theta) of one term.
struct Linearization {
  Eigen::Matrix<double, 2, 3> J_p2p;
  Point2 r_p2p;
  Eigen::Matrix<double, 1, 3> J_p2l;
  double r_p2l = 0.0;
};

Linearization linearize(const Term& term, const Eigen::Vector3d& x) {
  const Eigen::Matrix2d R = rotation(x.z());
  const Point2 Rp = R * term.p;
  const Point2 dRp = perpendicular(Rp);  // d(R p)/d theta
  const Point2 error = Rp + x.head<2>() - term.q1;
  Linearization out;
  out.r_p2p = error;
  out.J_p2p << 1.0, 0.0, dRp.x(), 0.0, 1.0, dRp.y();
  const Point2 n = term.normal();
  out.r_p2l = n.dot(error);
  out.J_p2l << n.x(), n.y(), n.dot(dRp);
  return out;
}

// d/dx of the term's cost w |r|^2: the gradient whose derivatives Eq. (6) needs.
Eigen::Vector3d cost_gradient(const Term& term, const Eigen::Vector3d& x, ErrorMetric metric) {
  const Linearization l = linearize(term, x);
  if (metric == ErrorMetric::kPointToPoint) return 2.0 * term.weight * l.J_p2p.transpose() * l.r_p2p;
  return 2.0 * term.weight * l.r_p2l * l.J_p2l.transpose();
}

std::optional<Term> make_term(const PointCloud2& target, const PointCloud2& source, const Correspondence& c,
                              ErrorMetric metric) {
  if (c.source >= source.size() || c.target >= target.size() || !(c.weight > 0.0)) return std::nullopt;
  Term term;
  term.p = source.points[c.source];
  term.q1 = target.points[c.target];
  term.weight = c.weight;
  if (metric == ErrorMetric::kPointToLine) {
    if (c.target2 != kNoPoint) {
      if (c.target2 >= target.size()) return std::nullopt;
      term.q2 = target.points[c.target2];
      term.segment = true;
    } else {
      if (c.target >= target.normals.size()) return std::nullopt;
      term.fixed_normal = target.normals[c.target];
    }
    if (term.normal().squaredNorm() < 0.5) return std::nullopt;
  }
  return term;
}

// Unit vector along which a range reading moves its point: the bearing from the sensor.
Point2 bearing_of(const Point2& point) {
  const double range = point.norm();
  return range > 1e-12 ? Point2(point / range) : Point2::Zero();
}

std::optional<Eigen::Matrix3d> inverse(const Eigen::Matrix3d& H) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
  const double scale = H.diagonal().cwiseAbs().maxCoeff();
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(scale > 0.0) ||
      ldlt.vectorD().minCoeff() <= 1e-12 * scale) {
    return std::nullopt;
  }
  Eigen::Matrix3d H_inv = ldlt.solve(Eigen::Matrix3d::Identity());
  H_inv = 0.5 * (H_inv + H_inv.transpose()).eval();
  if (!H_inv.allFinite()) return std::nullopt;
  return H_inv;
}

}  // namespace

Covariance3 censi_covariance(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                             const std::vector<Correspondence>& correspondences, ErrorMetric metric,
                             const SensorNoise& noise) {
  const Eigen::Vector3d x(T_target_source.x(), T_target_source.y(), T_target_source.theta());
  constexpr double h = 1e-6;  // m and rad, central differences of the analytic gradient
  Eigen::Matrix3d d2J_dx2 = Eigen::Matrix3d::Zero();
  // d2J/dz dx, one column per range reading: source points first, then target points.
  std::vector<Eigen::Vector3d> d2J_dzdx(source.size() + target.size(), Eigen::Vector3d::Zero());
  std::size_t terms = 0;
  for (const Correspondence& c : correspondences) {
    const std::optional<Term> term = make_term(target, source, c, metric);
    if (!term) continue;
    ++terms;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d dx = Eigen::Vector3d::Zero();
      dx[k] = h;
      d2J_dx2.col(k) += (cost_gradient(*term, x + dx, metric) - cost_gradient(*term, x - dx, metric)) / (2.0 * h);
    }
    // Each range reading moves its point along its bearing.
    const auto add_reading = [&](std::size_t column, Point2 Term::*point) {
      const Point2 along = bearing_of((*term).*point);
      Term plus = *term;
      Term minus = *term;
      plus.*point += h * along;
      minus.*point -= h * along;
      d2J_dzdx[column] += (cost_gradient(plus, x, metric) - cost_gradient(minus, x, metric)) / (2.0 * h);
    };
    add_reading(c.source, &Term::p);
    add_reading(source.size() + c.target, &Term::q1);
    if (term->segment) add_reading(source.size() + c.target2, &Term::q2);
  }
  if (terms < 3) return unknown_covariance();
  const std::optional<Eigen::Matrix3d> H_inv = inverse(0.5 * (d2J_dx2 + d2J_dx2.transpose()));
  if (!H_inv) return unknown_covariance();
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();  // (d2J/dzdx) cov(z) (d2J/dzdx)^T
  for (const Eigen::Vector3d& column : d2J_dzdx) spread += column * column.transpose();
  spread *= noise.range_sigma * noise.range_sigma;
  const Covariance3 covariance = *H_inv * spread * *H_inv;  // Eq. (6)
  return make_positive_definite(covariance, 1e-18);
}

Covariance3 hessian_covariance(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                               const std::vector<Correspondence>& correspondences, ErrorMetric metric) {
  const Eigen::Vector3d x(T_target_source.x(), T_target_source.y(), T_target_source.theta());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  double squared_sum = 0.0;
  std::size_t residuals = 0;
  std::size_t terms = 0;
  for (const Correspondence& c : correspondences) {
    const std::optional<Term> term = make_term(target, source, c, metric);
    if (!term) continue;
    ++terms;
    const Linearization l = linearize(*term, x);
    if (metric == ErrorMetric::kPointToPoint) {
      H += term->weight * l.J_p2p.transpose() * l.J_p2p;
      squared_sum += term->weight * l.r_p2p.squaredNorm();
      residuals += 2;
    } else {
      H += term->weight * l.J_p2l.transpose() * l.J_p2l;
      squared_sum += term->weight * l.r_p2l * l.r_p2l;
      residuals += 1;
    }
  }
  if (terms < 3 || residuals <= 3) return unknown_covariance();
  const std::optional<Eigen::Matrix3d> H_inv = inverse(H);
  if (!H_inv) return unknown_covariance();
  const double variance = squared_sum / static_cast<double>(residuals - 3);
  return make_positive_definite(variance * *H_inv, 1e-18);
}

double rms_residual(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                    const std::vector<Correspondence>& correspondences, ErrorMetric metric) {
  const Eigen::Vector3d x(T_target_source.x(), T_target_source.y(), T_target_source.theta());
  double squared_sum = 0.0;
  double weight_sum = 0.0;
  for (const Correspondence& c : correspondences) {
    const std::optional<Term> term = make_term(target, source, c, metric);
    if (!term) continue;
    const Linearization l = linearize(*term, x);
    const double squared = metric == ErrorMetric::kPointToPoint ? l.r_p2p.squaredNorm() : l.r_p2l * l.r_p2l;
    squared_sum += term->weight * squared;
    weight_sum += term->weight;
  }
  return weight_sum > 0.0 ? std::sqrt(squared_sum / weight_sum) : 0.0;
}

}  // namespace slam2d
