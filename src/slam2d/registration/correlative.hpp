// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Correlative scan matching: E. Olson, "Real-time correlative scan matching", ICRA 2009.
//
// The pose maximising the log-likelihood of the source points in the target's lookup table
// (correlative_grid.hpp) over a discrete window of poses around the guess:
//   T* = argmax_T sum_i s(cell(T p_i)),   T = (x0 + i dx, y0 + j dx, theta0 + k dtheta)   Eq. (2)
// with |i| <= nx, |j| <= ny, |k| <= nk. Three searches return the same pose and score:
// - exhaustive (Sec. III-C): every pose; the source is rotated once per angle, then slid;
// - multi-resolution (Sec. IV): every low-resolution voxel (D x D translations at one angle)
//   scored on the max-pooled table, an upper bound of the poses beneath; the voxels are then
//   visited in order of bound and searched at full resolution while their bound can still beat
//   the best score so far;
// - branch-and-bound (W. Hess et al., "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016,
//   Sec. V, Algorithm 3): depth-first over a quadtree of translation blocks per angle, bounded
//   by the max-pooled levels, best bound first, pruned by the best score so far.
// Ties (equal integer scores) go to the pose closest to the guess in steps, i^2 + j^2 + k^2,
// then to the smallest (k, j, i): every search returns the same, unique argmax.
//
// The covariance is Olson's Sec. III-D: p(T) proportional to exp(log-likelihood) over the
// evaluated poses, Sigma = K / s - u u^T / s^2 with s = sum p, u = sum p dT, K = sum p dT dT^T
// (Eq. (3)), dT the pose's offset (x, y, theta) from the best one. Exhaustive uses the whole
// window; the fast searches a box around the best pose scored at full resolution, each side
// doubled from one step while the response on its face is above 1e-3 of the best's, up to
// covariance_radius steps (so a flat direction, a corridor's axis, is measured, a peaked one
// costs 27 poses). The grid's own quantisation, one step wide, adds dx^2 / 12 and dtheta^2 / 12
// (a uniform error within a step) on the diagonal; an axis the window does not search (zero
// half-width) gets a huge variance (1e6) and no correlation.
//
// MatchResult: iterations = poses scored at any level (bounds included); inliers = source points
// in cells scoring above 0 (nearer a target point than the truncation d_max); residual (m) = the
// RMS distance of the inliers to their target point as read from the table (Eq. (1) inverted);
// converged = the best pose lies strictly inside the window (in every searched dimension) and its
// normalised score sum s / (kMaxCellScore n) is at least min_score. degenerate / weak_direction
// come from analyze_degeneracy (degeneracy.hpp) with each inlier paired to its nearest target
// point (the target's normals): the Fisher information of the scene's geometry.

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/correlative_grid.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

enum class CorrelativeSearch {
  kExhaustive,       // every pose of the window (Olson Sec. III-C)
  kMultiResolution,  // low-resolution voxels, then full resolution in order of bound (Olson Sec. IV)
  kBranchAndBound,   // a quadtree of max-pooled bounds, depth first (Hess 2016 Sec. V)
};
constexpr auto choices(CorrelativeSearch) {
  return std::array{Choice{"exhaustive", CorrelativeSearch::kExhaustive}, Choice{"multi_resolution", CorrelativeSearch::kMultiResolution}, Choice{"branch_and_bound", CorrelativeSearch::kBranchAndBound}};
}

struct CorrelativeConfig {
  // The lookup table, for the overload that builds it from the target cloud (a prebuilt grid
  // carries its own): see CorrelativeGridConfig.
  double resolution = 0.03;
  double sigma = 0.03;
  double truncation = 3.0;
  double max_segment_length = 0.0;
  int levels = 0;
  // The window around the guess (half-widths):
  double window_x = 0.3;
  double window_y = 0.3;
  double window_theta = 0.35;
  double linear_step = 0.0;
  double angular_step = 0.0;
  CorrelativeSearch search = CorrelativeSearch::kBranchAndBound;
  int low_resolution_steps = 16;
  double min_score = 0.3;
  int covariance_radius = 16;
  double min_eigenvalue_ratio = 0.01;
};

template <typename Fields>
void describe(Fields& f, CorrelativeConfig& c) {
  f.number("resolution", c.resolution, "m per cell", greater_than(0), "the lookup table built from the target cloud (Olson: 0.03)");
  f.number("sigma", c.sigma, "m", greater_than(0), "standard deviation of a point's distance to its target point");
  f.number("truncation", c.truncation, "sigmas", greater_than(0), "the log-likelihood is floored at d_max = truncation * sigma");
  f.number("max_segment_length", c.max_segment_length, "m", at_least(0), "target points closer than this are joined by a segment (0: points only)");
  f.number("levels", c.levels, "1", between(0, 16), "max-pooled table levels; 0: as many as the window and search need");
  f.number("window_x", c.window_x, "m", at_least(0), "half-width of the search window around the guess");
  f.number("window_y", c.window_y, "m", at_least(0), "");
  f.number("window_theta", c.window_theta, "rad", between(0, std::numbers::pi), "");
  f.number("linear_step", c.linear_step, "m", at_least(0), "0: the grid's resolution; else a whole multiple of it");
  f.number("angular_step", c.angular_step, "rad", at_least(0), "0: the farthest source point moves at most one linear step");
  f.choice("search", c.search, "every pose (Olson III-C), low-resolution voxels first (Olson IV), or branch and bound (Hess 2016)");
  f.number("low_resolution_steps", c.low_resolution_steps, "steps", between(2, 1 << 15), "linear steps per side of a multi-resolution voxel, a power of two");
  f.number("min_score", c.min_score, "1", between(0, 1), "normalised score below which the match has not converged");
  f.number("covariance_radius", c.covariance_radius, "steps", between(0, 50), "farthest the covariance box grows from the best pose (fast searches)");
  f.number("min_eigenvalue_ratio", c.min_eigenvalue_ratio, "1", open_interval(0, 1), "degeneracy threshold (DegeneracyConfig)");
}

/// The lookup-table part of a matcher configuration, with `levels` resolved (0: the levels the
/// window and search need).
CorrelativeGridConfig correlative_grid_config(const CorrelativeConfig& config);

/// Throws Error unless the configuration is valid (ranges on CorrelativeConfig).
void validate(const CorrelativeConfig& config);

/// Builds the table over `target` (correlative_grid_config(config)) and matches `source` in it.
/// Clouds are in their sensor frames. Fewer than 3 source points, or an empty target, give
/// converged = false with the guess and a huge covariance. Throws Error for an invalid
/// configuration or a non-finite point or guess.
MatchResult match_correlative(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                              const CorrelativeConfig& config = {});

/// Matches `source` in a prebuilt table (its resolution, sigma, truncation and levels; the
/// config's table fields are ignored). T_target_source maps source points into the grid's frame.
/// Searches that need more levels than the grid has use more, smaller top blocks (still exact).
MatchResult match_correlative(const CorrelativeGrid& grid, const PointCloud2& source, const SE2& T_target_source_guess,
                              const CorrelativeConfig& config = {});

}  // namespace slam2d
