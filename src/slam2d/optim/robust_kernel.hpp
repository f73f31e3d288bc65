// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Robust kernels for iteratively reweighted least squares: P. J. Huber, "Robust estimation of a
// location parameter", Ann. Math. Statist. 35(1), 1964; the Cauchy (Lorentzian) and Tukey
// biweight kernels as tabulated in Z. Zhang, "Parameter estimation techniques: a tutorial with
// application to conic fitting", Image and Vision Computing 15(1), 1997, Table 1.
//
// A kernel replaces the squared residual r^2 / 2 by rho(r). Gauss-Newton with IRLS weights
// w(r) = rho'(r) / r minimises sum rho(r_i): each residual enters the normal equations as
// H += w J^T J, b += w J^T r (normal_equations.hpp). `scale` (k) is in the residual's unit.

#include <array>

#include "slam2d/core/config_fields.hpp"

namespace slam2d {

enum class RobustKernelType {
  kNone,    // rho = r^2 / 2, w = 1
  kHuber,   // quadratic for |r| <= k, linear beyond
  kCauchy,  // rho = k^2 / 2 log(1 + (r / k)^2)
  kTukey,   // biweight: w = (1 - (r / k)^2)^2 for |r| <= k, 0 beyond
  kDcs,     // dynamic covariance scaling: w = s^2, s = min(1, 2 k^2 / (k^2 + r^2))
  kTls,     // truncated least squares: rho = min(r^2, k^2) / 2, w = 1 for |r| <= k, 0 beyond
};
constexpr auto choices(RobustKernelType) {
  return std::array{Choice{"none", RobustKernelType::kNone}, Choice{"huber", RobustKernelType::kHuber},
                    Choice{"cauchy", RobustKernelType::kCauchy}, Choice{"tukey", RobustKernelType::kTukey},
                    Choice{"dcs", RobustKernelType::kDcs}, Choice{"tls", RobustKernelType::kTls}};
}

struct RobustKernel {
  RobustKernelType type = RobustKernelType::kNone;
  double scale = 1.0;  // k

  /// The IRLS weight rho'(r) / r, in [0, 1] (1 for kNone, inline: the common case in hot loops).
  double weight(double residual) const { return type == RobustKernelType::kNone ? 1.0 : kernel_weight(residual); }
  /// The cost rho(r); r^2 / 2 for kNone, so all kernels agree with it near r = 0.
  double cost(double residual) const;

 private:
  double kernel_weight(double residual) const;  // weight() of the other kernels
};

/// The kernel on an odometry prior's Mahalanobis distance: Cauchy at 2 sigma, so the scan wins where
/// the odometry is many sigmas off (Hector's prior, picked as docs/defaults.md says; the RBPF's
/// per-scan matching with its prior from the learnt motion noise).
inline constexpr RobustKernel kOdometryPriorKernel{.type = RobustKernelType::kCauchy, .scale = 2.0};

template <typename Fields>
void describe(Fields& f, RobustKernel& c) {
  f.choice("type", c.type,
           "rho(r): none (r^2 / 2), huber, cauchy, tukey (biweight), dcs (dynamic covariance scaling) or tls (truncated "
           "least squares; the pose graph back end reaches it by graduated non-convexity)");
  f.number("scale", c.scale, "residual's unit", greater_than(0), "k: where the kernel departs from r^2 / 2");
}

double huber_weight(double residual, double scale);
double cauchy_weight(double residual, double scale);
double tukey_weight(double residual, double scale);
double dcs_weight(double residual, double scale);

/// Throws Error for a field out of its range (a non-finite or non-positive scale).
void validate(const RobustKernel& kernel);

}  // namespace slam2d
