// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The shared least-squares layer, in the shape of iris_lama's nlls/problem.h: residuals and
// Jacobians are accumulated into fixed-size normal equations, then one Gauss-Newton or
// Levenberg-Marquardt step is solved (K. Levenberg, Quart. Appl. Math. 2(2), 1944;
// D. W. Marquardt, J. SIAM 11(2), 1963).
//
// For residuals r_i(x) with Jacobians J_i = dr_i/dx and IRLS weights w_i (robust_kernel.hpp):
//   H = sum w_i J_i^T J_i,  b = sum w_i J_i^T r_i,  cost = sum w_i r_i^T r_i / 2,
// and the step dx solves (H + lambda D) dx = -b, with D = diag(H) (Marquardt's scaling) or the
// identity; lambda = 0 is Gauss-Newton. N is the parameter dimension (3 for an SE2 pose).

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <optional>

namespace slam2d {

template <int N>
struct NormalEquations {
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;
  using Row = Eigen::Matrix<double, 1, N>;

  Matrix H = Matrix::Zero();  // sum w J^T J
  Vector b = Vector::Zero();  // sum w J^T r
  double cost = 0.0;          // sum w r^T r / 2
  std::size_t residuals = 0;  // residual blocks added

  /// One scalar residual r with Jacobian row J and weight w >= 0.
  void add(const Row& J, double r, double w = 1.0) {
    H.noalias() += w * J.transpose() * J;
    b.noalias() += (w * r) * J.transpose();
    cost += 0.5 * w * r * r;
    ++residuals;
  }
  /// One M-dimensional residual block r with Jacobian J (M x N) and weight w >= 0.
  template <int M>
  void add(const Eigen::Matrix<double, M, N>& J, const Eigen::Matrix<double, M, 1>& r, double w = 1.0) {
    H.noalias() += w * J.transpose() * J;
    b.noalias() += w * J.transpose() * r;
    cost += 0.5 * w * r.squaredNorm();
    ++residuals;
  }
  /// Sums another accumulator into this one (e.g. partial sums of a parallel stage).
  void add(const NormalEquations& other) {
    H += other.H;
    b += other.b;
    cost += other.cost;
    residuals += other.residuals;
  }
};

enum class Damping {
  kDiagonal,  // D = diag(H): Marquardt's scale-invariant damping
  kIdentity,  // D = I: Levenberg's damping
};

struct StepConfig {
  double lambda = 0.0;                 // 1, damping; 0 is the Gauss-Newton step
  Damping damping = Damping::kDiagonal;
  double epsilon = 0.0;                // added to diag(H) in the damping term, kDiagonal: lambda (diag(H) + epsilon)
  double singular_pivot = 1e-12;       // 1: an LDL^T pivot at most this times the largest diagonal entry is
                                       // singular; 0: no singularity test, only a non-finite step fails
};

/// The step dx solving (H + lambda D) dx = -b (robust Cholesky, LDL^T), or nullopt when that
/// system is singular, not positive definite (both tested when singular_pivot > 0) or gives a
/// non-finite step.
template <int N>
std::optional<typename NormalEquations<N>::Vector> solve_step(const NormalEquations<N>& equations,
                                                               const StepConfig& config = {}) {
  using Matrix = typename NormalEquations<N>::Matrix;
  Matrix A = equations.H;
  if (config.lambda > 0.0) {
    if (config.damping == Damping::kDiagonal) {
      A.diagonal() += config.lambda * (equations.H.diagonal().array() + config.epsilon).matrix();
    } else {
      A.diagonal().array() += config.lambda;
    }
  }
  if (!A.allFinite() || !equations.b.allFinite()) return std::nullopt;
  const Eigen::LDLT<Matrix> ldlt(A);
  if (config.singular_pivot > 0.0) {
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
    // LDL^T reports success on a singular matrix: reject (near-)zero pivots relative to the scale of A.
    const double scale = A.diagonal().cwiseAbs().maxCoeff();
    if (!(scale > 0.0) || ldlt.vectorD().minCoeff() <= config.singular_pivot * scale) return std::nullopt;
  }
  const typename NormalEquations<N>::Vector dx = ldlt.solve(-equations.b);
  if (!dx.allFinite()) return std::nullopt;
  return dx;
}

/// H^-1, the covariance of a least-squares estimate whose residuals have unit variance (scale
/// it by the residual variance otherwise); nullopt when H is singular.
template <int N>
std::optional<typename NormalEquations<N>::Matrix> inverse_hessian(const NormalEquations<N>& equations) {
  using Matrix = typename NormalEquations<N>::Matrix;
  NormalEquations<N> unit = equations;
  unit.b.setZero();
  if (!solve_step(unit)) return std::nullopt;
  const Eigen::LDLT<Matrix> ldlt(equations.H);
  Matrix inverse = ldlt.solve(Matrix::Identity());
  inverse = 0.5 * (inverse + inverse.transpose()).eval();
  if (!inverse.allFinite()) return std::nullopt;
  return inverse;
}

}  // namespace slam2d
