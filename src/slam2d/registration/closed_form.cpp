// SPDX-License-Identifier: BSD-3-Clause
// Closed-form ICP steps: Arun 1987 / Umeyama 1991 (SVD), Besl & McKay 1992 Sec. III-C (unit
// quaternion), Low 2004 (point-to-plane linear least squares). See closed_form.hpp.

#include "slam2d/registration/closed_form.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

// Below this fraction of the largest eigenvalue of A^T A a direction is left out of the
// pseudo-inverse (Low's A^+): that direction is unconstrained and gets no motion.
constexpr double kPseudoInverseTolerance = 1e-12;

double weight_at(const std::vector<double>* weights, std::size_t i) { return weights ? (*weights)[i] : 1.0; }

void check_pairs(std::size_t targets, std::size_t sources, const std::vector<double>* weights) {
  check(targets == sources, "closed-form solver: target and source point lists differ in length");
  check(targets > 0, "closed-form solver: no point pairs");
  check(weights == nullptr || weights->size() == targets, "closed-form solver: one weight per pair is needed");
}

// The weighted centroids mu_p (source), mu_x (target) (Eq. (23)) and the cross-covariance
// Sigma_px = sum w (p - mu_p)(x - mu_x)^T / sum w (Eq. (24)).
struct CrossCovariance {
  Point2 mu_source = Point2::Zero();
  Point2 mu_target = Point2::Zero();
  Eigen::Matrix2d sigma = Eigen::Matrix2d::Zero();
};

CrossCovariance cross_covariance(const std::vector<Point2>& target_points, const std::vector<Point2>& source_points,
                                 const std::vector<double>* weights) {
  check_pairs(target_points.size(), source_points.size(), weights);
  CrossCovariance c;
  double total = 0.0;
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    const double w = weight_at(weights, i);
    check(w >= 0.0 && std::isfinite(w), "closed-form solver: weights must be finite and >= 0");
    c.mu_source += w * source_points[i];
    c.mu_target += w * target_points[i];
    total += w;
  }
  check(total > 0.0, "closed-form solver: the weights sum to zero");
  c.mu_source /= total;
  c.mu_target /= total;
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    c.sigma.noalias() +=
        weight_at(weights, i) * (source_points[i] - c.mu_source) * (target_points[i] - c.mu_target).transpose();
  }
  c.sigma /= total;
  return c;
}

// The optimal translation for the rotation theta: q_T = mu_x - R(q_R) mu_p (Eq. (26)).
SE2 with_optimal_translation(double theta, const CrossCovariance& c) {
  const SE2 rotation(0.0, 0.0, theta);
  return SE2(c.mu_target - rotation.act(c.mu_source), theta);
}

}  // namespace

SE2 solve_point_to_point_svd(const std::vector<Point2>& target_points, const std::vector<Point2>& source_points,
                             const std::vector<double>* weights) {
  const CrossCovariance c = cross_covariance(target_points, source_points, weights);
  // Sigma_px = U S V^T; R = V diag(1, det(V U^T)) U^T maximises tr(R Sigma_px) over rotations.
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(c.sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix2d& U = svd.matrixU();
  const Eigen::Matrix2d& V = svd.matrixV();
  const double reflection = (V * U.transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Eigen::Matrix2d R = V * Eigen::Vector2d(1.0, reflection).asDiagonal() * U.transpose();
  return with_optimal_translation(std::atan2(R(1, 0), R(0, 0)), c);
}

SE2 solve_point_to_point_quaternion(const std::vector<Point2>& target_points,
                                    const std::vector<Point2>& source_points, const std::vector<double>* weights) {
  const CrossCovariance c = cross_covariance(target_points, source_points, weights);
  // Sigma_px of the planar points embedded at z = 0, A = Sigma - Sigma^T, Delta = (A23, A31, A12).
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  sigma.topLeftCorner<2, 2>() = c.sigma;
  const Eigen::Matrix3d A = sigma - sigma.transpose();
  const Eigen::Vector3d delta(A(1, 2), A(2, 0), A(0, 1));
  // Eq. (25): Q = [tr(Sigma), Delta^T; Delta, Sigma + Sigma^T - tr(Sigma) I3].
  const double trace = sigma.trace();
  Eigen::Matrix4d Q;
  Q(0, 0) = trace;
  Q.block<1, 3>(0, 1) = delta.transpose();
  Q.block<3, 1>(1, 0) = delta;
  Q.block<3, 3>(1, 1) = sigma + sigma.transpose() - trace * Eigen::Matrix3d::Identity();
  // For planar points Q is block diagonal: (q0, q3), the rotations about z, and (q1, q2), the
  // half turns about in-plane axes, which mirror the plane and are no planar motion. The unit
  // eigenvector of the largest eigenvalue is taken in the first block.
  Eigen::Matrix2d block;
  block << Q(0, 0), Q(0, 3), Q(3, 0), Q(3, 3);
  if (block.cwiseAbs().maxCoeff() == 0.0) return with_optimal_translation(0.0, c);  // rotation undetermined
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(block);
  const Eigen::Vector2d q = solver.eigenvectors().col(1);  // (q0, q3), eigenvalues ascending
  return with_optimal_translation(2.0 * std::atan2(q(1), q(0)), c);  // Eq. (21): about z by 2 atan2(q3, q0)
}

SE2 solve_point_to_point(PointToPointSolver solver, const std::vector<Point2>& target_points,
                         const std::vector<Point2>& source_points, const std::vector<double>* weights) {
  return solver == PointToPointSolver::kQuaternion
             ? solve_point_to_point_quaternion(target_points, source_points, weights)
             : solve_point_to_point_svd(target_points, source_points, weights);
}

double mean_squared_distance(const SE2& T_target_source, const std::vector<Point2>& target_points,
                             const std::vector<Point2>& source_points, const std::vector<double>* weights) {
  check_pairs(target_points.size(), source_points.size(), weights);
  const Eigen::Matrix2d R = T_target_source.rotation();
  const Point2& t = T_target_source.translation();
  double sum = 0.0;
  double total = 0.0;
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    const double w = weight_at(weights, i);
    sum += w * (R * source_points[i] + t - target_points[i]).squaredNorm();
    total += w;
  }
  return total > 0.0 ? sum / total : 0.0;
}

std::optional<SE2> solve_point_to_plane(const std::vector<Point2>& target_points,
                                        const std::vector<Point2>& target_normals,
                                        const std::vector<Point2>& source_points, const std::vector<double>* weights) {
  check(target_points.size() == source_points.size() && target_normals.size() == source_points.size(),
        "solve_point_to_plane: target points, target normals and source points differ in length");
  check(weights == nullptr || weights->size() == source_points.size(),
        "solve_point_to_plane: one weight per pair is needed");
  if (source_points.size() < 3) return std::nullopt;
  // Low 2004, Sec. 2 in 2D: with R ~ [1 -g; g 1], (R s + t - d) . n ~ a . x - b with
  // a = (s_x n_y - s_y n_x, n_x, n_y), x = (g, t_x, t_y), b = n . (d - s); A stacks the rows a.
  Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    const Point2& s = source_points[i];
    const Point2& n = target_normals[i];
    const Eigen::Vector3d a(s.x() * n.y() - s.y() * n.x(), n.x(), n.y());
    const double b = n.dot(target_points[i] - s);
    const double w = weight_at(weights, i);
    AtA.noalias() += w * a * a.transpose();
    Atb += (w * b) * a;
  }
  // x_opt = A^+ b = (A^T A)^+ A^T b, directions without constraint left out.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(AtA);
  const Eigen::Vector3d& eigenvalues = solver.eigenvalues();
  if (!eigenvalues.allFinite() || !Atb.allFinite() || !(eigenvalues(2) > 0.0)) return std::nullopt;
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int j = 0; j < 3; ++j) {
    if (eigenvalues(j) <= kPseudoInverseTolerance * eigenvalues(2)) continue;
    const Eigen::Vector3d v = solver.eigenvectors().col(j);
    x += v * (v.dot(Atb) / eigenvalues(j));
  }
  return SE2(x(1), x(2), x(0));  // M = T(t) R(g) with the exact rotation
}

}  // namespace slam2d
