// SPDX-License-Identifier: BSD-3-Clause
// The shared least-squares layer: robust kernel weights against the derivative of their cost,
// normal equations against an explicit stacked Jacobian, the Gauss-Newton step against the exact
// linear least-squares solution, and Levenberg-Marquardt recovering known curve parameters.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/optim/levenberg_marquardt.hpp"
#include "slam2d/optim/normal_equations.hpp"
#include "slam2d/optim/robust_kernel.hpp"

namespace slam2d {
namespace {

class KernelTest : public ::testing::TestWithParam<RobustKernelType> {};

// IRLS needs w(r) = rho'(r) / r: checked by a central difference of the cost.
TEST_P(KernelTest, WeightIsTheCostDerivativeOverTheResidual) {
  const RobustKernel kernel{.type = GetParam(), .scale = 0.7};
  for (const double r : {-3.0, -0.9, -0.5, -0.1, 0.05, 0.3, 0.69, 0.71, 1.2, 5.0}) {
    const double h = 1e-6;
    const double derivative = (kernel.cost(r + h) - kernel.cost(r - h)) / (2.0 * h);
    EXPECT_NEAR(kernel.weight(r), derivative / r, 1e-6) << "r = " << r;
  }
}

TEST_P(KernelTest, MatchesTheQuadraticNearZeroAndNeverExceedsOne) {
  const RobustKernel kernel{.type = GetParam(), .scale = 2.0};
  EXPECT_NEAR(kernel.cost(1e-4), 0.5e-8, 1e-14);
  EXPECT_NEAR(kernel.weight(1e-4), 1.0, 1e-8);
  for (double r = -10.0; r <= 10.0; r += 0.25) {
    EXPECT_GE(kernel.weight(r), 0.0);
    EXPECT_LE(kernel.weight(r), 1.0);
  }
}

INSTANTIATE_TEST_SUITE_P(AllKernels, KernelTest,
                         ::testing::Values(RobustKernelType::kNone, RobustKernelType::kHuber, RobustKernelType::kCauchy,
                                           RobustKernelType::kTukey, RobustKernelType::kDcs,
                                           RobustKernelType::kTls));

TEST(RobustKernel, HandComputedWeights) {
  EXPECT_DOUBLE_EQ(huber_weight(0.5, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(huber_weight(4.0, 1.0), 0.25);
  EXPECT_DOUBLE_EQ(cauchy_weight(2.0, 1.0), 0.2);
  EXPECT_DOUBLE_EQ(tukey_weight(0.5, 1.0), 0.5625);
  EXPECT_DOUBLE_EQ(dcs_weight(0.5, 1.0), 1.0);   // chi2 0.25 <= Phi = 1: s = 1
  EXPECT_DOUBLE_EQ(dcs_weight(3.0, 1.0), 0.04);  // s = 2 / (1 + 9) = 0.2
  EXPECT_DOUBLE_EQ(tukey_weight(1.5, 1.0), 0.0);
  EXPECT_DOUBLE_EQ((RobustKernel{.type = RobustKernelType::kTls, .scale = 1.0}.weight(0.99)), 1.0);
  EXPECT_DOUBLE_EQ((RobustKernel{.type = RobustKernelType::kTls, .scale = 1.0}.weight(-1.01)), 0.0);
  EXPECT_DOUBLE_EQ((RobustKernel{.type = RobustKernelType::kTls, .scale = 1.0}.cost(7.0)), 0.5);
  EXPECT_THROW(validate(RobustKernel{.type = RobustKernelType::kHuber, .scale = 0.0}), Error);
  EXPECT_THROW(validate(RobustKernel{.type = RobustKernelType::kHuber, .scale = NAN}), Error);
}

TEST(NormalEquations, EqualTheStackedJacobianProducts) {
  Eigen::Matrix<double, 5, 3> J;
  J << 1, 2, 0, -1, 0.5, 3, 0, 1, 1, 2, -2, 0.25, 0.1, 0.2, 0.3;
  const Eigen::Matrix<double, 5, 1> r(0.5, -1.0, 2.0, 0.1, -0.3);
  const Eigen::Matrix<double, 5, 1> w(1.0, 0.5, 2.0, 0.0, 1.0);
  NormalEquations<3> equations;
  for (int i = 0; i < 5; ++i) equations.add(NormalEquations<3>::Row(J.row(i)), r(i), w(i));
  const Eigen::Matrix3d H = J.transpose() * w.asDiagonal() * J;
  const Eigen::Vector3d b = J.transpose() * w.asDiagonal() * r;
  EXPECT_TRUE(equations.H.isApprox(H, 1e-12));
  EXPECT_TRUE(equations.b.isApprox(b, 1e-12));
  EXPECT_NEAR(equations.cost, 0.5 * r.dot(w.asDiagonal() * r), 1e-12);
  EXPECT_EQ(equations.residuals, 5u);

  // A 2-row block gives the same sums as its two rows.
  NormalEquations<3> blocks;
  blocks.add(Eigen::Matrix<double, 2, 3>(J.topRows<2>()), Eigen::Vector2d(r.head<2>()), 1.0);
  NormalEquations<3> rows;
  rows.add(NormalEquations<3>::Row(J.row(0)), r(0));
  rows.add(NormalEquations<3>::Row(J.row(1)), r(1));
  EXPECT_TRUE(blocks.H.isApprox(rows.H, 1e-12));
  EXPECT_TRUE(blocks.b.isApprox(rows.b, 1e-12));
  NormalEquations<3> sum = rows;
  sum.add(blocks);
  EXPECT_TRUE(sum.H.isApprox(2.0 * rows.H, 1e-12));
}

TEST(SolveStep, GaussNewtonStepIsTheLinearLeastSquaresSolution) {
  // Residuals r(x) = A x - y are linear: one Gauss-Newton step from 0 lands on the solution.
  Eigen::Matrix<double, 6, 3> A;
  A << 1, 0, 2, 0, 1, 1, 3, 1, 0, 1, 1, 1, -1, 2, 0, 0, 0, 1;
  const Eigen::Vector3d truth(0.3, -1.2, 2.5);
  Eigen::Matrix<double, 6, 1> y = A * truth;
  y(2) += 0.01;  // inconsistent: a true least-squares problem
  NormalEquations<3> equations;
  for (int i = 0; i < 6; ++i) equations.add(NormalEquations<3>::Row(A.row(i)), -y(i));
  const auto dx = solve_step(equations);
  ASSERT_TRUE(dx.has_value());
  const Eigen::Vector3d expected = A.colPivHouseholderQr().solve(y);
  EXPECT_TRUE(dx->isApprox(expected, 1e-10));

  // Damping shortens the step towards zero.
  const auto damped = solve_step(equations, {.lambda = 10.0});
  ASSERT_TRUE(damped.has_value());
  EXPECT_LT(damped->norm(), dx->norm());
  const auto levenberg = solve_step(equations, {.lambda = 1e3, .damping = Damping::kIdentity});
  ASSERT_TRUE(levenberg.has_value());
  EXPECT_LT(levenberg->norm(), 0.1 * dx->norm());
}

TEST(SolveStep, SingularSystemsGiveNoStep) {
  NormalEquations<3> equations;
  equations.add(NormalEquations<3>::Row(1.0, 0.0, 0.0), 1.0);
  equations.add(NormalEquations<3>::Row(0.0, 1.0, 0.0), 1.0);  // nothing constrains the third parameter
  EXPECT_FALSE(solve_step(equations).has_value());
  EXPECT_FALSE(inverse_hessian(equations).has_value());
  EXPECT_TRUE(solve_step(equations, {.lambda = 1.0, .damping = Damping::kIdentity}).has_value());
  NormalEquations<3> nan_equations;
  nan_equations.add(NormalEquations<3>::Row(1.0, NAN, 0.0), 1.0);
  EXPECT_FALSE(solve_step(nan_equations).has_value());
}

TEST(SolveStep, InverseHessianInvertsH) {
  NormalEquations<2> equations;
  equations.add(NormalEquations<2>::Row(2.0, 1.0), 0.0);
  equations.add(NormalEquations<2>::Row(0.0, 3.0), 0.0);
  const auto inverse = inverse_hessian(equations);
  ASSERT_TRUE(inverse.has_value());
  EXPECT_TRUE((*inverse * equations.H).isApprox(Eigen::Matrix2d::Identity(), 1e-12));
}

// y = a exp(b t) + c sampled without noise: LM recovers (a, b, c) from a poor start.
TEST(LevenbergMarquardt, RecoversCurveParameters) {
  const Eigen::Vector3d truth(2.0, -0.7, 0.5);
  std::vector<double> t, y;
  for (int i = 0; i < 30; ++i) {
    t.push_back(0.2 * i);
    y.push_back(truth(0) * std::exp(truth(1) * t.back()) + truth(2));
  }
  const auto linearize = [&](const Eigen::Vector3d& x) {
    NormalEquations<3> equations;
    for (std::size_t i = 0; i < t.size(); ++i) {
      const double e = std::exp(x(1) * t[i]);
      equations.add(NormalEquations<3>::Row(e, x(0) * t[i] * e, 1.0), x(0) * e + x(2) - y[i]);
    }
    return equations;
  };
  const auto result = levenberg_marquardt<3>(linearize, Eigen::Vector3d(1.0, -0.2, 0.0), {.max_iterations = 100});
  EXPECT_TRUE(result.converged);
  EXPECT_TRUE(result.x.isApprox(truth, 1e-6)) << result.x.transpose();
  EXPECT_LT(result.cost, 1e-12);
}

}  // namespace
}  // namespace slam2d
