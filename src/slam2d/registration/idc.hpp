// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// IMRP and IDC: F. Lu and E. Milios, "Robot pose estimation in unknown environments by matching
// 2D range scans", Journal of Intelligent and Robotic Systems 18, 1997 (also CVPR 1994), Sec. 4.
//
// Equation numbers are this file's (the paper's sections are cited); docs/methods/idc.md maps
// them to the functions.
//
// Both scans are polylines through their points in beam order, broken where consecutive points
// are farther apart than `max_gap` (occlusions). For a source point p, m = T p in the target frame:
// - the closest-point rule (Sec. 4.1) pairs m with the closest point of the target polyline,
//   interpolated along a segment, within a distance threshold D:
//     c(m) = argmin_{q on polyline} |q - m|,  |c(m) - m| <= D                             Eq. (1)
// - the matching-range-point rule (Sec. 4.2): seen from the source sensor o = T.translation(),
//   m has range r = |m - o| and bearing phi; its pair is the point of the target polyline within
//   the bearing window [phi - B_r, phi + B_r] whose range is closest to r:
//     c'(m) = argmin_{q on polyline, |bearing_o(q) - phi| <= B_r} | |q - o| - r |          Eq. (2)
//   A rotation about the sensor keeps every range, so these pairs are exact up to the rotation,
//   which the bearing differences then give.
// The closest-point pairs (a_i, b_i) give the least-squares rigid motion D = (R(w), t) in
// closed form (fit_rigid_motion):
//     w = atan2(S_xy' - S_yx', S_xx' + S_yy'),  S_xy' = sum (x_i - x_mean)(y'_i - y'_mean) ...  Eq. (3)
//     t = b_mean - R(w) a_mean                                                              Eq. (4)
// The range rule's pairs (m_i, q_i) are solved along the normal n_i of q_i's target segment,
// about the source sensor o (one Gauss-Newton step, small rotation):
//     min_D sum (n_i^T (D m_i - q_i))^2,  D m = R(w) (m - o) + o + t                        Eq. (3')
//   (a deviation from the paper's point-to-point Eq. (3)-(4) for this rule, see
//   docs/methods/idc.md: a range pair's displacement runs across the beam, so point-to-point
//   also asserts zero radial motion at every pair; measured, IMRP then drifted 4 cm off the truth.)
// IMRP iterates the range rule alone: D from Eq. (3'). IDC (Sec. 4.3) computes both rules each
// iteration and takes the rotation w from the range rule (Eq. (3')) and the translation from the
// closest-point pairs, Eq. (4) with that rotation:
//     D = (b_cp_mean - R(w_range) a_cp_mean, w_range)                                      Eq. (5)
// The window B_r and the threshold D shrink exponentially with the iteration k:
//     B_r(k) = max(B_final, B_r(0) exp(-alpha k))                                          Eq. (6)
// Both stop when a step is below the tolerances or, once the bounds are at their floors, when
// the pose returns to one of the last two (the pairs alternate: PoseCycle, period 2).
// Clouds are in their sensor frames and in beam order (bearings ascending), as to_point_cloud
// gives them; the projective closest-point search relies on that order (it falls back to a
// linear search for unordered clouds).
//
// Every MatchResult is complete: at the estimate the closest-point pairs give the inliers, the
// residual (RMS distance to the interpolated target polyline), the covariance (censi_covariance,
// kPointToLine against each pair's segment) and the degeneracy verdict (analyze_degeneracy with
// the same pairs against normals fitted over 7 points along the target: two-point segment
// normals of a noisy scan would lend a corridor information along its axis).

#include <numbers>
#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct ImrpConfig {
  int max_iterations = 60;
  double window_initial = 0.35;
  double window_final = 0.02;
  double window_decay = 0.15;
  double max_range_difference = 0.1;
  double max_gap = 0.5;
  double final_max_distance = 0.3;
  double translation_tolerance = 1e-4;
  double rotation_tolerance = 1e-5;
  int min_correspondences = 6;
  double range_sigma = 0.01;
};

// The fields IMRP and IDC share, in the order of their tables.
template <typename Fields, typename Config>
void describe_range_rule(Fields& f, Config& c) {
  f.number("window_initial", c.window_initial, "rad", open_interval(0, std::numbers::pi / 2), "the range rule's window B_r(0)");
  f.number("window_final", c.window_final, "rad", greater_than(0), "the floor of B_r, <= window_initial");
  f.number("window_decay", c.window_decay, "1/iteration", at_least(0), "alpha of the window, Eq. (6)");
}
template <typename Fields, typename Config>
void describe_polylines(Fields& f, Config& c) {
  f.number("max_range_difference", c.max_range_difference, "m", greater_than(0), "range-rule pairs whose ranges differ more are dropped");
  f.number("max_gap", c.max_gap, "m", greater_than(0), "polylines break between consecutive points farther apart");
}
template <typename Fields, typename Config>
void describe_stop(Fields& f, Config& c) {
  f.number("translation_tolerance", c.translation_tolerance, "m", at_least(0), "converged when a step moves the source sensor less ...");
  f.number("rotation_tolerance", c.rotation_tolerance, "rad", at_least(0), "... and turns it less");
  f.number("min_correspondences", c.min_correspondences, "1", at_least(3), "fewer pairs (of either rule) end the match unconverged");
  f.number("range_sigma", c.range_sigma, "m", greater_than(0), "range noise for the covariance");
}

template <typename Fields>
void describe(Fields& f, ImrpConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "");
  describe_range_rule(f, c);
  describe_polylines(f, c);
  f.number("final_max_distance", c.final_max_distance, "m", greater_than(0), "closest-point threshold at the estimate (result statistics)");
  describe_stop(f, c);
}

struct IdcConfig {
  int max_iterations = 40;
  double window_initial = 0.35;
  double window_final = 0.02;
  double window_decay = 0.15;
  double max_distance_initial = 1.0;
  double max_distance_final = 0.2;
  double max_distance_decay = 0.15;
  double max_range_difference = 0.1;
  double max_gap = 0.5;
  double translation_tolerance = 1e-4;
  double rotation_tolerance = 1e-5;
  int min_correspondences = 6;
  double range_sigma = 0.01;
};

template <typename Fields>
void describe(Fields& f, IdcConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "");
  describe_range_rule(f, c);
  f.number("max_distance_initial", c.max_distance_initial, "m", greater_than(0), "closest-point threshold at t = 0");
  f.number("max_distance_final", c.max_distance_final, "m", greater_than(0), "its floor, <= max_distance_initial");
  f.number("max_distance_decay", c.max_distance_decay, "1/iteration", at_least(0), "alpha of the threshold");
  describe_polylines(f, c);
  describe_stop(f, c);
}

/// Throw Error naming the first invalid field.
void validate(const ImrpConfig& config);
void validate(const IdcConfig& config);

/// Iterative matching-range-point (Lu & Milios Sec. 4.2): the range rule alone.
MatchResult match_imrp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                       const ImrpConfig& config = {});

/// Iterative dual correspondence (Lu & Milios Sec. 4.3): rotation from the range rule,
/// translation from the closest-point rule.
MatchResult match_idc(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                      const IdcConfig& config = {});

// ---- The building blocks, shared with tangent_search.hpp and tested on their own. ----

/// A scan as a polyline in beam order: segment k joins point k and point k + 1 when they are at
/// most max_gap apart. Bearings are from the scan's origin (its sensor), unwrapped.
struct ScanPolyline {
  std::vector<Point2> points;            // m, the scan's points in its own frame
  std::vector<unsigned char> connected;  // connected[k]: segment k exists (size: points - 1, or 0)
  std::vector<double> bearings;          // rad, unwrapped bearing of each point
  std::vector<Point2> directions;        // unit vectors along the bearings
  bool ordered = true;                   // bearings strictly ascending: the projective search applies
};

ScanPolyline make_scan_polyline(const PointCloud2& cloud, double max_gap);

/// A point on a polyline: on segment `segment` at `s` in [0, 1] (s = 0 with an isolated point).
struct PolylinePoint {
  std::size_t segment = kNoPoint;  // index of the segment's first point
  double s = 0.0;                  // 1, position along the segment
  Point2 point = Point2::Zero();   // m, in the polyline's frame
  double distance = 0.0;           // m, from the query (closest-point rule) or |range difference| (range rule)
  double bearing_difference = 0.0; // rad, bearing of `point` minus the query's (range rule only)
};

/// The closest-point rule: the point of the polyline closest to `query` (polyline frame), if
/// one is within max_distance. Projective search outward from the query's bearing when ordered.
std::optional<PolylinePoint> closest_point(const ScanPolyline& polyline, const Point2& query, double max_distance);

/// The matching-range-point rule for every source point: with m = T p in the target frame and the
/// source sensor at o = T.translation(), the point q of the target polyline with bearing (seen from
/// o) within +-window of m's and | |q - o| - |m - o| | smallest (ties: the smaller bearing
/// difference), kept when that range difference is at most max_range_difference. Entry i is for
/// source point i (nullopt: no match).
std::vector<std::optional<PolylinePoint>> matching_range_points(const ScanPolyline& target, const PointCloud2& source,
                                                                const SE2& T_target_source, double window,
                                                                double max_range_difference);

/// The least-squares rigid motion D minimising sum |D a_i - b_i|^2 over point pairs, in closed
/// form (Eq. (3)-(4)); nullopt with fewer than 2 pairs.
std::optional<SE2> fit_rigid_motion(const std::vector<Point2>& a, const std::vector<Point2>& b,
                                    const std::vector<double>& weights = {});

/// Fills inliers, residual, covariance (Censi, point-to-line) and the degeneracy verdict (fitted
/// normals, polyline neighbours within max_gap) of `result` from the closest-point pairs at
/// result.T_target_source within max_distance.
void finish_with_closest_points(const PointCloud2& target, const ScanPolyline& target_polyline,
                                const PointCloud2& source, double max_distance, double max_gap, double range_sigma,
                                MatchResult& result);

}  // namespace slam2d
