// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Boolean (binary) and soft-weighted ICP, as compared in the 2013 ICP-SLAM work on a bi-steerable
// robot, written as the six-step ICP framework of S. Rusinkiewicz and M. Levoy, "Efficient
// variants of the ICP algorithm", 3DIM 2001 (Sec. 2):
//   1. select   source points: all of them, or every k-th           select_points
//   2. match    each to its closest target point (kd-tree)          match_closest_points
//   3. weight   the pairs                                           weight_pairs, pair_weight
//                 Boolean: w = 1 if d <= d_w, else 0                 Eq. (1)
//                 soft:    w = 1 - d / d_w (R&L's linear weight),    Eq. (2)
//                          exp(-d^2 / (2 d_w^2)) or 1 / (1 + (d / d_w)^2)
//   4. reject   pairs farther than d_max, beyond mean + k sigma of the kept distances, or with
//               incompatible normals                                 reject_pairs
//   5. error    point-to-point  sum w |T p - q|^2                    Eq. (3)
//               point-to-line   sum w (n^T (T p - q))^2               Eq. (4)
//   6. minimise point-to-point: the weighted closed form (Arun/Umeyama SVD, solve_point_to_point_svd)
//               point-to-line: Low 2004's linearised least squares at the estimate
//               (solve_point_to_plane), one step per iteration; both from closed_form.hpp
// iterated from the guess until the update is below the tolerances. d is the distance of the
// pair at the current estimate. The framework paper states these steps in prose; the equation
// numbers are this file's own (docs/methods/weighted_icp.md lists them).
//
// The final correspondences are re-associated at the estimate; the covariance is Censi's closed
// form for the minimised metric (covariance.hpp), the residual their weighted RMS, and the
// degeneracy analysis uses the target's normals (fitted to the k nearest neighbours when absent,
// normals.hpp).

#include <numbers>
#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

enum class IcpWeighting {
  kBoolean,  // w in {0, 1}: the pair is in or out, Eq. (1)
  kSoft,     // w in [0, 1], decreasing with the pair distance, Eq. (2)
};
constexpr auto choices(IcpWeighting) {
  return std::array{Choice{"boolean", IcpWeighting::kBoolean}, Choice{"soft", IcpWeighting::kSoft}};
}

enum class SoftWeightKernel {
  kLinear,    // w = max(0, 1 - d / d_w): Rusinkiewicz & Levoy's "linear" weighting
  kGaussian,  // w = exp(-d^2 / (2 d_w^2))
  kCauchy,    // w = 1 / (1 + (d / d_w)^2)
};
constexpr auto choices(SoftWeightKernel) {
  return std::array{Choice{"linear", SoftWeightKernel::kLinear}, Choice{"gaussian", SoftWeightKernel::kGaussian}, Choice{"cauchy", SoftWeightKernel::kCauchy}};
}

struct WeightedIcpConfig {
  IcpWeighting weighting = IcpWeighting::kBoolean;
  // 1. select
  int select_every = 1;
  // 3. weight
  double weight_distance = 0.3;
  SoftWeightKernel soft_kernel = SoftWeightKernel::kLinear;
  // 4. reject
  double max_correspondence_distance = 1.0;
  double reject_sigma_factor = 0.0;
  double max_normal_angle = 0.0;
  // 5. error metric
  ErrorMetric metric = ErrorMetric::kPointToPoint;
  int normal_neighbors = 5;
  double normal_max_distance = 0.5;
  // 6. minimise, stop
  int max_iterations = 50;
  double translation_tolerance = 1e-4;
  double rotation_tolerance = 1e-4;
  int min_correspondences = 10;
  double range_sigma = 0.01;
};

template <typename Fields>
void describe(Fields& f, WeightedIcpConfig& c) {
  f.choice("weighting", c.weighting, "Boolean or soft (match_boolean_icp / match_soft_icp force it)");
  f.number("select_every", c.select_every, "1", at_least(1), "1. select: every k-th source point is used");
  f.number("weight_distance", c.weight_distance, "m", greater_than(0), "3. weight: d_w, the Boolean threshold and the soft kernel's scale");
  f.choice("soft_kernel", c.soft_kernel, "the soft weight's shape");
  f.number("max_correspondence_distance", c.max_correspondence_distance, "m", greater_than(0), "4. reject: d_max, farther pairs are rejected");
  f.number("reject_sigma_factor", c.reject_sigma_factor, "1", at_least(0), "k: reject d > mean + k std of the kept distances (0: off)");
  f.number("max_normal_angle", c.max_normal_angle, "rad", between(0, std::numbers::pi), "reject pairs whose normals differ more (0: off)");
  f.choice("metric", c.metric, "5. error metric: point-to-point or point-to-line (target normals)");
  f.number("normal_neighbors", c.normal_neighbors, "1", at_least(3), "k nearest points (itself included) in a normal fit");
  f.number("normal_max_distance", c.normal_max_distance, "m", greater_than(0), "neighbours farther are left out of a normal fit");
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "6. minimise, stop");
  f.number("translation_tolerance", c.translation_tolerance, "m", at_least(0), "converged when an update moves less ...");
  f.number("rotation_tolerance", c.rotation_tolerance, "rad", at_least(0), "... and turns less");
  f.number("min_correspondences", c.min_correspondences, "1", at_least(3), "fewer pairs with w > 0 is a failure");
  f.number("range_sigma", c.range_sigma, "m", greater_than(0), "range noise for Censi's covariance");
}

/// Throws Error naming the first invalid field.
void validate(const WeightedIcpConfig& config);

/// The weight of a pair at distance `distance` (m) under the config's weighting, Eq. (1)-(2).
double pair_weight(double distance, const WeightedIcpConfig& config);

/// ICP with the weighting of config.weighting.
MatchResult match_weighted_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                               const WeightedIcpConfig& config = {});

/// Boolean-weighted ICP (config.weighting is taken as kBoolean). CLI name: boolean-icp.
MatchResult match_boolean_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                              const WeightedIcpConfig& config = {});

/// Soft-weighted ICP (config.weighting is taken as kSoft). CLI name: soft-icp.
MatchResult match_soft_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                           const WeightedIcpConfig& config = {});

}  // namespace slam2d
