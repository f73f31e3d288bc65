// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Is the match constrained in every direction? The Fisher information of the pose from
// point-to-line residuals (A. Censi, "On achievable accuracy for range-finder localization",
// ICRA 2007): each matched point i, at m_i = T p_i in the target frame with the target's
// surface normal n_i there, contributes
//   I += a_i a_i^T / sigma^2,  a_i = ( n_i, n_i^T J (m_i - t) ),  J = [0 -1; 1 0].
// A corridor gives no information along its axis and a circular room none in rotation. The
// eigen-decomposition, with rotation scaled to arc length at the points' RMS distance L from
// the sensor (theta' = L theta, so every axis is in metres), names the weak direction; the
// match is degenerate when the smallest eigenvalue is below `min_eigenvalue_ratio` times the
// largest.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct DegeneracyConfig {
  double min_eigenvalue_ratio = 0.01;
  double range_sigma = 0.01;
};

template <typename Fields>
void describe(Fields& f, DegeneracyConfig& c) {
  f.number("min_eigenvalue_ratio", c.min_eigenvalue_ratio, "1", between(0, 1), "smallest over largest scaled eigenvalue below which the match is degenerate");
  f.number("range_sigma", c.range_sigma, "m", greater_than(0), "sensor noise that scales the information");
}

struct DegeneracyAnalysis {
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  // Fisher information in (x, y, theta): 1/m^2, 1/(m rad), 1/rad^2
  double length_scale = 1.0;                               // m, L above
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();   // 1/m^2, ascending, of the scaled information
  Eigen::Matrix3d directions = Eigen::Matrix3d::Identity();  // columns: unit eigenvectors in (x, y, theta), matching eigenvalues
  bool degenerate = true;
  Eigen::Vector3d weak_direction = Eigen::Vector3d::Zero();  // (x, y, theta), unit, the first column of directions
};

/// Normals come from `target.normals` (point-to-line with target2 = kNoPoint, or any
/// point-to-point pair; estimated with estimate_normals when the target has none) or from the
/// segment target-target2; pairs without a normal are skipped.
/// With fewer than 3 usable pairs the match is degenerate.
DegeneracyAnalysis analyze_degeneracy(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source,
                                      const std::vector<Correspondence>& correspondences,
                                      const DegeneracyConfig& config = {});

/// The decomposition of a given information matrix (x, y, theta) at length scale L.
DegeneracyAnalysis analyze_information(const Eigen::Matrix3d& information, double length_scale,
                                       const DegeneracyConfig& config = {});

/// What the scan's own geometry fixes, in the scan's frame. Its surfaces are the runs of points in
/// beam order joined by gaps under 0.5 m, three points or more; `information` holds each of their
/// points against its surface there, the chord through its neighbours up to four beams either side,
/// a_i a_i^T / sigma^2 with a_i = (n_i, n_i^T J p_i) (analyze_information decomposes it); `edges`
/// counts the depth edges, where a surface ends and the next one (behind at most eight lone
/// returns: mixed pixels) does not go on along its line. A corridor's walls give nothing along its
/// axis, also where a grid map built from one viewpoint holds a far wall as dots a beam apart,
/// which pin a scan from farther down the corridor to that viewpoint; an edge (a door frame, the
/// end of an occluding wall) does fix it, and is a surface's end the information leaves out. Lone
/// points (a mixed pixel, a far spurious return, the far dots themselves) add nothing; they are
/// counted (`lone_returns` of `returns`).
struct ScanGeometry {
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  std::size_t edges = 0;
  std::size_t lone_returns = 0;  // points on no surface
  std::size_t returns = 0;       // all the scan's points
};
ScanGeometry scan_geometry(const std::vector<Eigen::Vector2d>& points_in_beam_order, const DegeneracyConfig& config = {});

/// The translation a scan's geometry leaves open: the weak eigenvector (unit, in the scan's frame)
/// of its translational information with the rotation marginalised (the Schur complement
/// I_tt - I_ttheta I_thetatheta^-1 I_thetat), when its eigenvalue is below `ratio` times the strong
/// one's, no depth edge is in view and at most a quarter of the scan's returns are lone; none
/// otherwise. Where more are lone the surfaces are not what holds the scan: outdoors a trunk or a
/// pole is a lone return that fixes what a stretch of hedge leaves open (Freiburg campus, whose
/// scans hold 9 to 100 returns within 25 m, up to 95 % lone; a corridor's far dots are a tenth to a
/// seventh of its scan).
std::optional<Eigen::Vector2d> open_translation(const ScanGeometry& geometry, double ratio);

/// A pose increment (x, y, theta) without its translation along the unit direction w.
inline Eigen::Vector3d without_translation_along(Eigen::Vector3d increment, const Eigen::Vector2d& w) {
  increment.head<2>() -= w.dot(increment.head<2>()) * w;
  return increment;
}

/// Copies the verdict into a result (degenerate, weak_direction, information_eigenvalues) and, when degenerate, raises the
/// result's variance along the weak direction w to at least the Cramer-Rao bound 1 / (w^T I w)
/// and at least the variance along the strongest direction times the eigenvalue ratio (1e6 when
/// w carries no information).
void apply(const DegeneracyAnalysis& analysis, MatchResult& result);

}  // namespace slam2d
