// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How uncertain is an ICP estimate? Two estimates from a matcher's final correspondences:
//
// - Censi's closed form (A. Censi, "An accurate closed-form estimate of ICP's covariance",
//   ICRA 2007): with J(z, x) the error function over the measurements z at the estimate x,
//     cov(x) ~= (d2J/dx2)^-1 (d2J/dz dx) cov(z) (d2J/dz dx)^T (d2J/dx2)^-1        Eq. (6)
//   for the point-to-point and the point-to-line metric. The measurements z are the ranges of
//   source and target points (noise along each point's bearing from its cloud's origin, the
//   sensor), so the estimate follows from the sensor noise, not from the residuals.
// - The Hessian estimate: s^2 H^-1, with H the Gauss-Newton Hessian of the metric and s^2 the
//   residual variance (sum of squared residuals / (n - 3)). Cheap; it assumes the residuals are
//   independent noise, which overconfident associations violate.

#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

inline constexpr std::size_t kNoPoint = std::numeric_limits<std::size_t>::max();

/// One pair of the final association: source point `source` against target point `target`
/// (point-to-point), or against the line through target points `target` and `target2`
/// (point-to-line), or, for point-to-line with target2 = kNoPoint, against the line through
/// `target` along that point's normal (target.normals). `weight` is the matcher's weight (>= 0).
struct Correspondence {
  std::size_t source = 0;
  std::size_t target = 0;
  std::size_t target2 = kNoPoint;
  double weight = 1.0;
};

enum class ErrorMetric {
  kPointToPoint,  // |T p - q|^2
  kPointToLine,   // (n^T (T p - q))^2
};
constexpr auto choices(ErrorMetric) {
  return std::array{Choice{"point_to_point", ErrorMetric::kPointToPoint}, Choice{"point_to_line", ErrorMetric::kPointToLine}};
}

struct SensorNoise {
  double range_sigma = 0.01;  // m, standard deviation of a range reading
};

/// Censi 2007, Eq. (6), at T_target_source for the given correspondences and metric. The
/// clouds are in their sensor frames (the noise of point p lies along p / |p|). Returns a huge
/// diagonal (1e6) when fewer than 3 correspondences or a singular Hessian leave it undefined.
Covariance3 censi_covariance(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                             const std::vector<Correspondence>& correspondences, ErrorMetric metric,
                             const SensorNoise& noise = {});

/// s^2 H^-1 at T_target_source (huge diagonal when undefined, as above).
Covariance3 hessian_covariance(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                               const std::vector<Correspondence>& correspondences, ErrorMetric metric);

/// The weighted RMS residual (m) of the correspondences at T_target_source under the metric.
double rms_residual(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                    const std::vector<Correspondence>& correspondences, ErrorMetric metric);

}  // namespace slam2d
