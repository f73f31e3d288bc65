// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Hector scan-to-map matching: S. Kohlbrecher, O. von Stryk, J. Meyer, U. Klingauf, "A flexible
// and scalable SLAM system with full 3D motion estimation", SSRR 2011, Sec. IV-B and IV-C.
//
// The pose xi = (p_x, p_y, psi) (T_map_robot) maps the robot-frame end points s_i to
//   S_i(xi) = R(psi) s_i + (p_x, p_y)                                                     Eq. (7)
// and the matcher minimises sum_i (1 - M(S_i(xi)))^2 (Eq. 8) over the bilinearly interpolated
// occupancy probability M (grid/bilinear.hpp). The Gauss-Newton step is
//   dxi = H^-1 sum_i [grad M(S_i) dS_i/dxi]^T (1 - M(S_i)),                                Eq. (12)-(13)
//   H = sum_i [grad M(S_i) dS_i/dxi]^T [grad M(S_i) dS_i/dxi],
//   dS_i/dxi = [1 0 -sin(psi) s_x - cos(psi) s_y; 0 1 cos(psi) s_x - sin(psi) s_y],       Eq. (14)
// accumulated in optim/normal_equations.hpp (hector_linearize: the cost) and iterated by the shared
// driver optim/levenberg_marquardt.hpp in plain Gauss-Newton mode, with step clamps, step halving,
// solution remapping and an optional pose prior. On a map pyramid the coarsest level is matched
// first and each level's result starts the next (Sec. IV-C).
//
// The MatchResult: T_target_source is T_map_robot; covariance s^2 H^-1 on the finest level
// (unknown when H is singular or there are <= 3 points); converged: the finest level's last step
// was small; degenerate: H was singular on the finest level (the pose was not fully improved; the
// RBPF's proposal relies on this meaning); weak_direction: the least constrained direction of the
// scan's information (registration/degeneracy.hpp), also when not degenerate;
// iterations: Gauss-Newton steps over all levels; inliers: the end points (all are residuals);
// residual: the RMS of r = 1 - M (1, not m; the prior's cost included); cost: sum r^2 / 2 plus the
// prior's, on the finest level.

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/map_pyramid.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/optim/normal_equations.hpp"
#include "slam2d/optim/robust_kernel.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct HectorMatcherConfig {
  int coarse_iterations = 3;         // Gauss-Newton steps on every level but the finest, >= 1 (Hector: 3)
  int fine_iterations = 5;           // Gauss-Newton steps on the finest level, >= 1 (Hector: 5)
  double max_rotation_step = 0.2;    // rad, clamp on |d psi| per step (Hector: 0.2)
  double max_translation_step = 1.0; // cells of the level, clamp on |d p| per step (the bilinear gradient
                                     // only reaches about a cell from a wall: longer steps are extrapolation;
                                     // the clamp stops slides along degenerate corridors)
  double convergence_step = 1e-5;    // m and rad: a level stops when the step is smaller
  int max_step_halvings = 2;         // a step that raises the cost is halved up to this often, else dropped
  RobustKernel kernel{};             // on r = 1 - M; kNone is the paper's plain least squares
  // Multi-start on the coarsest level (an addition to the paper, for low-rate logs without
  // odometry): the guess rotated by k * rotation_search_step for |k step| <= rotation_search_range
  // is matched there and the lowest-cost result goes on to the finer levels. 0 disables it.
  // Picked on Intel, ACES and FR079, not yet checked on a held-out log (docs/defaults.md).
  double rotation_search_range = 0.2;  // rad, >= 0
  double rotation_search_step = 0.1;   // rad, > 0
  double rotation_search_margin = 0.0; // 1, in [0, 1): relative cost drop a rotated start needs to win
  // A rotated start that ends farther from the pose prior than the prior kernel's scale contradicts
  // the odometry; it wins only if it explains the scan: at least this share of the points on the
  // map's occupied cells (interpolated occupancy above kExplainedOccupancy). A lower cost alone is
  // no evidence against the odometry's heading: on a scan the map cannot explain (new ground, a
  // sparse outdoor view) a turned pose lowers it by moving points from free into unknown space or
  // onto scattered clutter (Freiburg campus with its exact odometry: 5-12 deg turns, graph SLAM
  // 6.05 m ATE). Without a prior there is nothing to contradict. 0: the lower cost wins.
  // Picked on Freiburg campus and Intel with its odometry shifted (docs/defaults.md).
  double rotation_search_min_explained = 0.5;  // 1, in [0, 1]
  // Solution remapping (J. Zhang, M. Kaess, S. Singh, "On degeneracy of optimization-based state
  // estimation problems", ICRA 2016; not in Hector): each step is projected onto the eigenvectors
  // of the scan's own information (H without the prior) whose eigenvalue exceeds this fraction of
  // the largest, so that along a corridor's axis the pose stays at the guess (the prediction)
  // instead of following the map's weak, possibly wrong pull. 0 disables it (Hector).
  double degeneracy_ratio = 0.0;       // 1, in [0, 1)
  // The same remapping, for the translation the scan's own geometry leaves open, whatever the
  // map's gradient claims: the weak direction of the scan's translational Fisher information
  // (registration/degeneracy.hpp's scan_geometry, the rotation marginalised) when its eigenvalue
  // is below this ratio times the strong one's and no depth edge is in view. A grid map built from
  // one viewpoint down a featureless corridor holds the far walls, which the beams reach at grazing
  // angles, as dots a beam apart; their gradient pins a scan taken farther down the corridor to that
  // viewpoint (the hospital world: the RBPF stood still for 8 scans at a time). The guess (the
  // prediction) keeps that direction. Scans of the three public logs never fall below 0.01
  // (Intel's lowest 0.02, ACES's 0.04, FR079's 0.12; the hospital world's plain corridor
  // 0.003-0.006). 0 disables it (the matcher's default; Hector, graph SLAM's tracker and the RBPF use
  // 0.01: docs/defaults.md).
  double scan_degeneracy_ratio = 0.0;  // 1, in [0, 1)
};

template <typename Fields>
void describe(Fields& f, HectorMatcherConfig& c) {
  f.number("coarse_iterations", c.coarse_iterations, "1", at_least(1), "Gauss-Newton steps on every level but the finest (Hector: 3)");
  f.number("fine_iterations", c.fine_iterations, "1", at_least(1), "Gauss-Newton steps on the finest level (Hector: 5)");
  f.number("max_rotation_step", c.max_rotation_step, "rad", greater_than(0), "clamp on |d psi| per step (Hector: 0.2)");
  f.number("max_translation_step", c.max_translation_step, "cells of the level", greater_than(0),
           "clamp on |d p| per step (the bilinear gradient reaches about a cell from a wall: longer steps are extrapolation)");
  f.number("convergence_step", c.convergence_step, "m and rad", at_least(0), "a level stops when the step is smaller");
  f.number("max_step_halvings", c.max_step_halvings, "1", at_least(0), "a step that raises the cost is halved up to this often, else dropped");
  f.section("kernel", c.kernel, "on r = 1 - M; none is the paper's plain least squares");
  f.number("rotation_search_range", c.rotation_search_range, "rad", at_least(0), "multi-start on the coarsest level over the guess rotated by k * step (0: off)");
  f.number("rotation_search_step", c.rotation_search_step, "rad", greater_than(0), "");
  f.number("rotation_search_margin", c.rotation_search_margin, "1", closed_open(0, 1), "relative cost drop a rotated start needs to win");
  f.number("rotation_search_min_explained", c.rotation_search_min_explained, "1", between(0, 1),
           "share of the scan a rotated start beyond the prior kernel's scale must put on occupied cells to win (0: the lower cost wins)");
  f.number("degeneracy_ratio", c.degeneracy_ratio, "1", closed_open(0, 1),
           "solution remapping (Zhang et al. 2016): steps projected onto the scan's eigenvectors above this fraction of the largest (0: off)");
  f.number("scan_degeneracy_ratio", c.scan_degeneracy_ratio, "1", closed_open(0, 1),
           "steps lose the translation the scan's own geometry leaves open: its translational information's weak over strong eigenvalue below this (0: off)");
}

/// An optional Gaussian prior on the pose (not in the paper): adds the residual xi - mean with
/// weight `information` (1/m^2, 1/rad^2) to the normal equations, so that directions the scan
/// leaves undetermined (a corridor's axis) follow the motion prediction instead of staying put.
/// The kernel acts on the prior's Mahalanobis distance m = sqrt(r^T information r) (IRLS weight
/// kernel.weight(m)): with a Cauchy kernel the prior gives way where the scan shows the
/// prediction many sigmas off (odometry counting a reverse as forward driving); kNone keeps the
/// plain Gaussian.
struct PosePrior {
  SE2 mean;
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  RobustKernel kernel{};
};

/// The prior's Mahalanobis distance sqrt(r^T information r) at pose xi, r = xi - mean (angle wrapped).
double prior_distance(const SE2& T_map_robot, const PosePrior& prior);

/// Adds the prior's residual at pose xi to the equations.
void add_pose_prior(NormalEquations<3>& equations, const SE2& T_map_robot, const PosePrior& prior);

/// The interpolated occupancy above which a scan point counts as explained by the map: more likely
/// occupied than not, on or beside an occupied cell (a wall's face reads about 0.55, half a cell
/// before the cell's centre), never in unknown (exactly 0.5) or free space.
inline constexpr double kExplainedOccupancy = 0.5;

/// The share of the points that land on the map's occupied cells at T_map_robot (0 for none).
double explained_share(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot);

/// Throws Error for iteration counts < 1 or a non-positive, non-finite step clamp.
void validate(const HectorMatcherConfig& config);

/// The normal equations of Eq. (12)-(13) at pose `T_map_robot` for one grid: residual
/// r_i = 1 - M(S_i), Jacobian dr_i/dxi = -grad M(S_i) dS_i/dxi, weights from the kernel.
NormalEquations<3> hector_linearize(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                                    const SE2& T_map_robot, const RobustKernel& kernel = {});

/// The translation the scan's own geometry leaves open (registration/degeneracy.hpp's
/// open_translation at config.scan_degeneracy_ratio; none when that is 0): a unit direction in the
/// scan's frame, which the matcher's steps do not move along.
std::optional<Eigen::Vector2d> scan_open_translation(const std::vector<Eigen::Vector2d>& points_robot,
                                                     const HectorMatcherConfig& config);

/// `iterations` Gauss-Newton steps on one grid from `T_map_robot_guess`.
MatchResult match_scan_to_grid(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                               const SE2& T_map_robot_guess, int iterations, const HectorMatcherConfig& config = {},
                               const std::optional<PosePrior>& prior = {});

/// Coarse to fine over the pyramid's levels (coarse_iterations steps each, fine_iterations on
/// level 0); the covariance is that of level 0. Fewer than 3 points return the guess, degenerate,
/// with an unknown covariance.
MatchResult match_scan_to_pyramid(const MapPyramid& pyramid, const std::vector<Eigen::Vector2d>& points_robot,
                                  const SE2& T_map_robot_guess, const HectorMatcherConfig& config = {},
                                  const std::optional<PosePrior>& prior = {});

/// Hector's fit measure: the mean of (1 - M)^2 over the end points on the finest level (the
/// prior's cost included), 2 cost / inliers; 0 for no points.
inline double mean_squared_residual(const MatchResult& hector_match) {
  return 2.0 * hector_match.cost / static_cast<double>(std::max<std::size_t>(hector_match.inliers, 1));
}

}  // namespace slam2d
