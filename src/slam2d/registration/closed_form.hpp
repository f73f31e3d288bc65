// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Closed-form solvers for one step of the ICP family in the plane, shared by icp, trimmed_icp,
// point_to_plane and any other matcher that has paired points:
//
// - point to point by SVD of the cross-covariance: K. S. Arun, T. S. Huang, S. D. Blostein,
//   "Least-squares fitting of two 3-D point sets", IEEE PAMI 9(5), 1987, and S. Umeyama,
//   "Least-squares estimation of transformation parameters between two point patterns",
//   IEEE PAMI 13(4), 1991 (the reflection guard);
// - point to point by the unit quaternion: P. J. Besl and N. D. McKay, "A method for registration
//   of 3-D shapes", IEEE PAMI 14(2), 1992, Sec. III-C, Eqs. (21)-(26) (after B. K. P. Horn,
//   JOSA A 4(4), 1987), the points lying in the plane z = 0;
// - point to plane by linear least squares: K.-L. Low, "Linear least-squares optimization for
//   point-to-plane ICP surface registration", TR04-004, UNC Chapel Hill, 2004, in 2D.
//
// Both point-to-point solvers return the exact minimiser of
//   f(T) = sum_i w_i |R p_i + t - x_i|^2                                  (Besl & McKay Eq. (22))
// over rotations (det R = +1) and translations; they agree to rounding.

#include <optional>
#include <vector>

#include <array>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

enum class PointToPointSolver {
  kSvd,         // Arun / Umeyama: SVD of the 2x2 cross-covariance
  kQuaternion,  // Besl & McKay Sec. III-C: the top eigenvector of the 4x4 matrix Q(Sigma_px)
};
constexpr auto choices(PointToPointSolver) {
  return std::array{Choice{"svd", PointToPointSolver::kSvd}, Choice{"quaternion", PointToPointSolver::kQuaternion}};
}

/// The T (= T_target_source) minimising sum_i w_i |T source_points[i] - target_points[i]|^2,
/// by SVD. `weights` (>= 0, positive sum) default to 1. The point lists must have the same,
/// non-zero length (else Error). With one pair, or all source points equal, the rotation is
/// not determined and the identity rotation is returned with the aligning translation.
SE2 solve_point_to_point_svd(const std::vector<Point2>& target_points, const std::vector<Point2>& source_points,
                             const std::vector<double>* weights = nullptr);

/// The same minimiser by Besl & McKay's unit quaternion (Eqs. (24)-(26)).
SE2 solve_point_to_point_quaternion(const std::vector<Point2>& target_points,
                                    const std::vector<Point2>& source_points,
                                    const std::vector<double>* weights = nullptr);

/// Dispatches to one of the two above.
SE2 solve_point_to_point(PointToPointSolver solver, const std::vector<Point2>& target_points,
                         const std::vector<Point2>& source_points, const std::vector<double>* weights = nullptr);

/// Weighted mean of |T source_points[i] - target_points[i]|^2 (m^2): Besl & McKay's d_k.
double mean_squared_distance(const SE2& T_target_source, const std::vector<Point2>& target_points,
                             const std::vector<Point2>& source_points, const std::vector<double>* weights = nullptr);

/// Low 2004 in 2D: the motion T minimising sum_i w_i ((T s_i - d_i) . n_i)^2 under the
/// small-angle approximation R ~ [1 -g; g 1], solved as the 3x3 linear system
/// A^T A x = A^T b for x = (g, t_x, t_y) by the pseudo-inverse (Low's x_opt = A^+ b), and
/// returned with the exact rotation by g. The solve is linearised at the identity: pass the
/// source points already moved by the current estimate and compose the result on the left
/// (T_new = result * T_current). d_i = target_points[i], n_i = target_normals[i] (unit),
/// s_i = source_points[i]. Nullopt with fewer than 3 pairs or no constraint at all; the lists
/// must have the same length (else Error).
std::optional<SE2> solve_point_to_plane(const std::vector<Point2>& target_points,
                                        const std::vector<Point2>& target_normals,
                                        const std::vector<Point2>& source_points,
                                        const std::vector<double>* weights = nullptr);

}  // namespace slam2d
