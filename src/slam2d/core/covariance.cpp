// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/covariance.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

Covariance3 covariance_from_sigmas(double sigma_x, double sigma_y, double sigma_theta) {
  return Eigen::Vector3d(sigma_x * sigma_x, sigma_y * sigma_y, sigma_theta * sigma_theta).asDiagonal();
}

Covariance3 propagate(const Covariance3& cov, const Matrix3& J) { return J * cov * J.transpose(); }

Covariance3 compose_covariance(const SE2& a, const Covariance3& cov_a, const SE2& b, const Covariance3& cov_b) {
  Matrix3 J_a, J_b;
  a.compose(b, &J_a, &J_b);
  return propagate(cov_a, J_a) + propagate(cov_b, J_b);
}

Covariance3 inverse_covariance(const SE2& a, const Covariance3& cov_a) {
  Matrix3 J;
  a.inverse(&J);
  return propagate(cov_a, J);
}

Covariance3 rotate_covariance(const Covariance3& cov, double angle) {
  Matrix3 R = Matrix3::Identity();
  R.topLeftCorner<2, 2>() = SE2(0.0, 0.0, angle).rotation();
  return propagate(cov, R);
}

bool is_valid_covariance(const Covariance3& cov, double tolerance) {
  if (!cov.allFinite()) return false;
  const double scale = std::max(1.0, cov.cwiseAbs().maxCoeff());
  if ((cov - cov.transpose()).cwiseAbs().maxCoeff() > tolerance * scale) return false;
  Eigen::SelfAdjointEigenSolver<Matrix3> solver(cov);
  return solver.eigenvalues().minCoeff() >= -tolerance * scale;
}

Covariance3 make_positive_definite(const Covariance3& cov, double min_eigenvalue) {
  const Matrix3 symmetric = 0.5 * (cov + cov.transpose());
  Eigen::SelfAdjointEigenSolver<Matrix3> solver(symmetric);
  const Eigen::Vector3d clamped = solver.eigenvalues().cwiseMax(min_eigenvalue);
  return solver.eigenvectors() * clamped.asDiagonal() * solver.eigenvectors().transpose();
}

Eigen::Matrix3d information_from_covariance(const Covariance3& cov) {
  Eigen::FullPivLU<Matrix3> lu(cov);
  check(lu.isInvertible(), "information_from_covariance: singular covariance");
  return lu.inverse();
}

double chi_square_quantile(double dof, double z) {
  const double a = 2.0 / (9.0 * dof);
  const double b = std::max(0.0, 1.0 - a + std::sqrt(a) * z);
  return dof * b * b * b;
}

Ellipse translation_ellipse(const Covariance3& cov) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(cov.topLeftCorner<2, 2>());
  const Eigen::Vector2d values = solver.eigenvalues().cwiseMax(0.0);  // ascending
  const Eigen::Vector2d major_axis = solver.eigenvectors().col(1);
  return {std::sqrt(values(1)), std::sqrt(values(0)), std::atan2(major_axis.y(), major_axis.x())};
}

}  // namespace slam2d
