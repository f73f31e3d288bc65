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

#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

enum class IcpWeighting {
  kBoolean,  // w in {0, 1}: the pair is in or out, Eq. (1)
  kSoft,     // w in [0, 1], decreasing with the pair distance, Eq. (2)
};

enum class SoftWeightKernel {
  kLinear,    // w = max(0, 1 - d / d_w): Rusinkiewicz & Levoy's "linear" weighting
  kGaussian,  // w = exp(-d^2 / (2 d_w^2))
  kCauchy,    // w = 1 / (1 + (d / d_w)^2)
};

struct WeightedIcpConfig {
  IcpWeighting weighting = IcpWeighting::kBoolean;  // Boolean or soft (match_boolean_icp / match_soft_icp force it)
  // 1. select
  int select_every = 1;  // 1, every k-th source point is used, >= 1
  // 3. weight
  double weight_distance = 0.3;                       // m, d_w: the Boolean threshold and the soft kernel's scale, > 0
  SoftWeightKernel soft_kernel = SoftWeightKernel::kLinear;  // the soft weight's shape
  // 4. reject
  double max_correspondence_distance = 1.0;  // m, d_max: farther pairs are rejected, > 0
  double reject_sigma_factor = 0.0;          // 1, k: reject d > mean + k std of the kept distances, >= 0 (0: off)
  double max_normal_angle = 0.0;             // rad, reject pairs whose normals differ more, in [0, pi] (0: off)
  // 5. error metric
  ErrorMetric metric = ErrorMetric::kPointToPoint;  // point-to-point or point-to-line (target normals)
  int normal_neighbors = 5;             // 1, k nearest points (itself included) in a normal fit, >= 3
  double normal_max_distance = 0.5;     // m, neighbours farther are left out of a normal fit, > 0
  // 6. minimise, stop
  int max_iterations = 50;              // 1, >= 1
  double translation_tolerance = 1e-4;  // m, converged when an update moves less, >= 0
  double rotation_tolerance = 1e-4;     // rad, ... and turns less, >= 0
  int min_correspondences = 10;         // 1, fewer pairs with w > 0 is a failure, >= 3
  double range_sigma = 0.01;            // m, range noise for Censi's covariance, > 0
};

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
