// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// 3x3 covariance helpers for poses (x, y, theta): m^2, m*rad, rad^2.

#include <Eigen/Core>

#include "slam2d/core/se2.hpp"

namespace slam2d {

using Covariance3 = Eigen::Matrix3d;

/// The variance (m^2, m rad, rad^2) that says "unknown": what a result reports for a direction
/// nothing constrained (an estimator that failed, an empty scan). One value for every method.
inline constexpr double kUnknownVariance = 1e6;
/// kUnknownVariance times the identity.
inline Covariance3 unknown_covariance() { return Covariance3::Identity() * kUnknownVariance; }

/// Diagonal covariance from standard deviations (m, m, rad).
Covariance3 covariance_from_sigmas(double sigma_x, double sigma_y, double sigma_theta);

/// J * cov * J^T: first-order propagation through a function with Jacobian J.
Covariance3 propagate(const Covariance3& cov, const Matrix3& J);

/// Covariance of a * b for independent a and b (first order).
Covariance3 compose_covariance(const SE2& a, const Covariance3& cov_a, const SE2& b, const Covariance3& cov_b);

/// Covariance of a^-1 (first order).
Covariance3 inverse_covariance(const SE2& a, const Covariance3& cov_a);

/// The covariance rotated into another frame: R cov R^T with R = diag(rotation, 1).
Covariance3 rotate_covariance(const Covariance3& cov, double angle);

/// True when symmetric (to a relative tolerance) and positive semi-definite.
bool is_valid_covariance(const Covariance3& cov, double tolerance = 1e-9);

/// Symmetric part with eigenvalues clamped to at least `min_eigenvalue`.
Covariance3 make_positive_definite(const Covariance3& cov, double min_eigenvalue = 1e-12);

/// The information matrix cov^-1 of a positive definite covariance.
Eigen::Matrix3d information_from_covariance(const Covariance3& cov);

/// The quantile of chi-square with `dof` degrees of freedom at the probability whose standard
/// normal quantile is z (3.09: 99.9 %), by Wilson and Hilferty's cube-root normal approximation
/// (within 2 % of the exact quantile from 3 degrees of freedom on, 0.2 % from 30): a Mahalanobis
/// gate.
double chi_square_quantile(double dof, double z);

/// The 1-sigma ellipse of the translational block: semi-axes (m) and the major axis angle (rad).
struct Ellipse {
  double major = 0.0;
  double minor = 0.0;
  double angle = 0.0;
};
Ellipse translation_ellipse(const Covariance3& cov);

}  // namespace slam2d
