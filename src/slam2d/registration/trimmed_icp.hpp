// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Trimmed ICP: D. Chetverikov, D. Svirko, D. Stepanov, P. Krsek, "The Trimmed Iterative Closest
// Point algorithm", ICPR 2002. Least trimmed squares: each iteration pairs every source (data)
// point with its closest target (model) point, keeps the N_po = xi N_p pairs with the smallest
// squared distances and registers them in closed form (closed_form.hpp). The overlap xi is given
// (`overlap`) or, with `overlap = 0`, chosen each iteration from the sorted residuals as the
// minimiser of their objective
//   psi(xi) = e(xi) / xi^(1 + lambda),   e(xi) = the trimmed MSE of the xi N_p best pairs,
// over xi in [min_overlap, 1] (their lambda = 2). Stops on their three criteria: the iteration
// limit, a small trimmed MSE, or a small relative change of it.
//
// When psi is minimised: the paper evaluates psi at converged registrations (one TrICP run per
// xi tried). `kAtConvergence` (default) does that cheaply: it starts with xi = 1, and each time
// the iteration has converged for the current xi it minimises psi over the sorted residuals
// there; a different xi continues the iteration from that pose, the same xi ends it.
// `kPerIteration` re-estimates xi at every iteration instead; far from the solution it keeps
// the pairs that happen to fit already and stops early (docs/methods/icp.md has the figures).
//
// Preset: configs/trimmed-icp.yaml. Method page: docs/methods/icp.md.

#include <array>
#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/closed_form.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

enum class OverlapEstimation {
  kAtConvergence,  // psi minimised where the iteration has converged for the current xi
  kPerIteration,   // psi minimised at every iteration
};
constexpr auto choices(OverlapEstimation) {
  return std::array{Choice{"at_convergence", OverlapEstimation::kAtConvergence}, Choice{"per_iteration", OverlapEstimation::kPerIteration}};
}

struct TrimmedIcpConfig {
  double overlap = 0.0;
  double min_overlap = 0.4;
  double lambda = 2.0;
  OverlapEstimation overlap_estimation = OverlapEstimation::kAtConvergence;
  int max_iterations = 300;
  double min_trimmed_mse = 1e-12;
  double min_relative_change = 1e-6;
  int min_correspondences = 10;
  PointToPointSolver solver = PointToPointSolver::kSvd;
};

template <typename Fields>
void describe(Fields& f, TrimmedIcpConfig& c) {
  f.number("overlap", c.overlap, "1", between(0, 1), "the fraction xi of source points kept; 0 = estimate it");
  f.number("min_overlap", c.min_overlap, "1", open_closed(0, 1), "lower end of the xi search when estimated");
  f.number("lambda", c.lambda, "1", greater_than(0), "exponent of psi(xi) = e / xi^(1 + lambda) (paper: 2)");
  f.choice("overlap_estimation", c.overlap_estimation, "when psi is minimised, with overlap = 0");
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "registrations before giving up (N_iter; 0.3 m off takes ~150)");
  f.number("min_trimmed_mse", c.min_trimmed_mse, "m^2", at_least(0), "stop when the trimmed MSE e falls below");
  f.number("min_relative_change", c.min_relative_change, "1", at_least(0), "stop when |e' - e| / e falls below");
  f.number("min_correspondences", c.min_correspondences, "1", at_least(3), "fewer kept pairs and the match fails");
  f.choice("solver", c.solver, "closed-form registration (same answer)");
}

/// Throws Error when a field is out of its range.
void validate(const TrimmedIcpConfig& config);

/// The number of pairs N_po = xi N_p minimising psi(xi) = e(xi) / xi^(1 + lambda) over
/// xi = n / N_p in [min_overlap, 1] (n >= 1), for the squared residuals sorted ascending;
/// ties go to the larger n. 0 for an empty list.
std::size_t trimmed_pair_count(const std::vector<double>& sorted_squared_distances, double min_overlap,
                               double lambda);

/// Registers `source` to `target` (both in their sensor frames) from the guess. The final
/// correspondences are the kept pairs at the estimate (`inliers` = N_po); residual is the RMS of
/// their distances; covariance is Censi's closed form for the point-to-point metric over them.
MatchResult match_trimmed_icp(const PointCloud2& target, const PointCloud2& source,
                              const SE2& T_target_source_guess, const TrimmedIcpConfig& config = {});

}  // namespace slam2d
