// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PL-ICP, ICP with a point-to-line metric: A. Censi, "An ICP variant using a point-to-line
// metric", ICRA 2008. Preset: configs/pl-icp.yaml; method page: docs/methods/pl_icp.md.
//
// The equations, numbered as marked in pl_icp.cpp (the paper's Sec. II, Algorithm 1, and its
// appendix on the exact minimisation):
//   (1) p_i^w = R(theta_k) p_i + t_k: the source points at the current estimate q_k.
//   (2) j1 = argmin_j |p_i^w - p_j|, j2 = the closer of j1's two scan neighbours: the segment
//       (p_j1, p_j2) stands for the target surface near p_i^w, n_i its unit normal.
//   (3) trimming: keep the pairs whose distance to their segment is at most
//       min(e_(maxPerc), mult * e_(order)), e_(f) the f-quantile of the distances.
//   (4) q_{k+1} = argmin_q sum_i w_i (n_i^T [R(theta) p_i^w + t - p_j1])^2, exactly: with
//       x = (t_x, t_y, cos theta, sin theta) the cost is x^T M x + g^T x + c, to be minimised
//       subject to x^T W x = 1, W = diag(0, 0, 1, 1). The Lagrange condition
//       (2 M + 2 lambda W) x = -g                                                     (5)
//       leaves, after eliminating t, the 2x2 Schur complement S and h (pl_icp.cpp), and the
//       constraint |(S + lambda I)^-1 h|^2 / 4 = 1 becomes the quartic
//       det(S + lambda I)^2 - |(adj S + lambda I) h|^2 / 4 = 0,                      (6)
//       whose real roots are the candidates; the one of least cost wins.
//   (7) stop when the step is below epsilon_xy and epsilon_theta, or when an association seen
//       before comes back (a fixed point or a cycle; CSM detects such loops the same way).
//
// The projective search of Eq. (2) (CSM's "correspondence tricks") walks the ordered target
// scan up and down from the previous iteration's match (or from the bearing of p_i^w), skipping
// runs of points with the jump tables (the next point farther / nearer from the sensor on either
// side) and stopping each side with the bound |p| sin(delta bearing). It is exact: it finds the
// same j1 as the kd-tree (see pl_icp_search.cpp for the bounds, a slight sharpening of CSM's).
// Bearings are compared as pseudo-angles (monotone in the bearing, a half turn = 2), one division
// each. Two exact shortcuts keep it cheap: a branch-free scan of a few points around the start,
// kept when the same bounds rule out everything outside it, and a clearance certificate (every
// other target point is at least c away from where the point was searched), which keeps j1
// without any search while the point has drifted less than c - |p - p_j1| since.

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

enum class PlIcpSearch {
  kProjective,  // Censi's ordered-scan search with jump tables (clouds in beam order)
  kKdTree,      // nearest neighbour by kd-tree (any cloud order)
};
constexpr auto choices(PlIcpSearch) {
  return std::array{Choice{"projective", PlIcpSearch::kProjective}, Choice{"kdtree", PlIcpSearch::kKdTree}};
}

struct PlIcpConfig {
  int max_iterations = 50;
  double epsilon_xy = 1e-4;
  double epsilon_theta = 1e-4;
  double max_correspondence_distance = 0.5;
  double max_segment_length = 1.0;
  double outliers_max_fraction = 0.95;
  double outliers_adaptive_order = 0.7;
  double outliers_adaptive_mult = 2.0;
  bool outliers_remove_doubles = true;
  PlIcpSearch search = PlIcpSearch::kProjective;
  int min_correspondences = 10;
  double range_sigma = 0.01;
};

template <typename Fields>
void describe(Fields& f, PlIcpConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "(CSM sm2: 1000; converges in about 5 on Intel: docs/methods/pl_icp.md)");
  f.number("epsilon_xy", c.epsilon_xy, "m", at_least(0), "stop when the step's translation is below this ...");
  f.number("epsilon_theta", c.epsilon_theta, "rad", at_least(0), "... and its rotation below this (CSM: 1e-4, 1e-4)");
  f.number("max_correspondence_distance", c.max_correspondence_distance, "m", greater_than(0), "j1 farther than this from p_i^w gives no pair");
  f.number("max_segment_length", c.max_segment_length, "m", greater_than(0), "pairs whose segment ends j1, j2 lie farther apart are dropped");
  f.number("outliers_max_fraction", c.outliers_max_fraction, "1", open_closed(0, 1), "trim all but this best fraction (CSM outliers_maxPerc)");
  f.number("outliers_adaptive_order", c.outliers_adaptive_order, "1", open_closed(0, 1), "quantile of the adaptive threshold (CSM: 0.7)");
  f.number("outliers_adaptive_mult", c.outliers_adaptive_mult, "1", greater_than(0), "adaptive threshold = mult * that quantile (CSM: 2)");
  f.flag("outliers_remove_doubles", c.outliers_remove_doubles, "of source points sharing a j1, keep only the closest (CSM: true)");
  f.choice("search", c.search, "correspondence search: Censi's projective one (clouds in beam order) or a kd-tree");
  f.number("min_correspondences", c.min_correspondences, "1", at_least(3), "fewer pairs and the match fails");
  f.number("range_sigma", c.range_sigma, "m", greater_than(0), "range noise for the covariance (Censi 2007)");
}

/// Throws Error for values outside the ranges above.
void validate(const PlIcpConfig& config);

/// PL-ICP from the guess. Clouds are in their sensor frames (the origin is the sensor); the
/// projective search needs the target in scan order (bearings increasing), and otherwise falls
/// back to the kd-tree. Normals are not used (the segments give them). The result's covariance is
/// Censi 2007's closed form for the point-to-line metric, its residual the RMS point-to-line
/// distance of the final inliers; clouds with fewer than 3 usable points (or fewer pairs than
/// min_correspondences) give converged = false with the guess and a huge covariance.
MatchResult match_pl_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                         const PlIcpConfig& config = {});

/// Eq. (2) alone: for every source point (moved by T_target_source) with a target point within
/// max_correspondence_distance, the pair (source i, closest target j1, its closer scan neighbour
/// j2 or kNoPoint), before any rejection; by config.search. Target points within 1 mm of the
/// sensor are ignored. For tests and diagnostics.
std::vector<Correspondence> pl_icp_correspondences(const PointCloud2& target, const PointCloud2& source,
                                                   const SE2& T_target_source, const PlIcpConfig& config = {});

/// The point-to-line objective sum_i w_i (n_i^T (R p_i + t - q_i))^2 of Eq. (4) as the quadratic
/// form x^T M x + g^T x + c in x = (t_x, t_y, cos theta, sin theta).
struct PointToLineProblem {
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  Eigen::Vector4d g = Eigen::Vector4d::Zero();
  double c = 0.0;
  std::size_t terms = 0;

  /// Adds w (n^T (R p + t - q))^2; n should be a unit vector (m).
  void add(const Point2& p, const Point2& q, const Point2& n, double w = 1.0);
  /// The objective at T (m^2).
  double cost(const SE2& T) const;
};

/// Eq. (5)-(6): the exact minimiser over (t, theta). A tiny ridge (1e-9 of the scale of M)
/// pulls directions the lines leave free (a corridor's axis, a circle's rotation) to the
/// identity, so the result is always defined; nullopt only for an empty or non-finite problem.
std::optional<SE2> minimize_point_to_line(const PointToLineProblem& problem);

/// The real roots of a x^4 + b x^3 + c x^2 + d x + e (a != 0), by Ferrari's method with a
/// Newton polish; returns their count (0 to 4) in roots[0..count).
int solve_quartic(double a, double b, double c, double d, double e, double roots[4]);

}  // namespace slam2d
