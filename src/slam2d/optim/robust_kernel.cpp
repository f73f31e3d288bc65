// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/optim/robust_kernel.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

double huber_weight(double residual, double scale) {
  const double a = std::abs(residual);
  return a <= scale ? 1.0 : scale / a;
}

double cauchy_weight(double residual, double scale) {
  const double u = residual / scale;
  return 1.0 / (1.0 + u * u);
}

double tukey_weight(double residual, double scale) {
  const double u = residual / scale;
  if (std::abs(u) > 1.0) return 0.0;
  const double v = 1.0 - u * u;
  return v * v;
}

// P. Agarwal, G. D. Tipaldi, L. Spinello, C. Stachniss, W. Burgard, "Robust map optimization using
// dynamic covariance scaling", ICRA 2013: the error scaled by s = min(1, 2 Phi / (Phi + chi2)),
// the closed-form optimum of a switchable constraint's switch; Phi = k^2 (chi2 = r^2). As IRLS,
// the weight is s^2.
double dcs_weight(double residual, double scale) {
  const double phi = scale * scale;
  const double s = std::min(1.0, 2.0 * phi / (phi + residual * residual));
  return s * s;
}

double RobustKernel::kernel_weight(double residual) const {
  switch (type) {
    case RobustKernelType::kHuber: return huber_weight(residual, scale);
    case RobustKernelType::kCauchy: return cauchy_weight(residual, scale);
    case RobustKernelType::kTukey: return tukey_weight(residual, scale);
    case RobustKernelType::kDcs: return dcs_weight(residual, scale);
    case RobustKernelType::kTls: return std::abs(residual) <= scale ? 1.0 : 0.0;
    case RobustKernelType::kNone: break;
  }
  return 1.0;
}

double RobustKernel::cost(double residual) const {
  const double k = scale;
  const double a = std::abs(residual);
  switch (type) {
    case RobustKernelType::kHuber: return a <= k ? 0.5 * a * a : k * (a - 0.5 * k);
    case RobustKernelType::kCauchy: return 0.5 * k * k * std::log1p((a / k) * (a / k));
    case RobustKernelType::kTukey: {
      if (a > k) return k * k / 6.0;
      const double v = 1.0 - (a / k) * (a / k);
      return k * k / 6.0 * (1.0 - v * v * v);
    }
    case RobustKernelType::kDcs: {  // the integral of r w(r): quadratic to r = k, then bounded by 3 k^2 / 2
      const double phi = k * k;
      return a <= k ? 0.5 * a * a : 1.5 * phi - 2.0 * phi * phi / (phi + a * a);
    }
    case RobustKernelType::kTls: return 0.5 * std::min(a, k) * std::min(a, k);
    case RobustKernelType::kNone: break;
  }
  return 0.5 * a * a;
}

void validate(const RobustKernel& kernel) {
  check_fields(kernel, "RobustKernel");
}

}  // namespace slam2d
