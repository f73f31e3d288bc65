#pragma once
// The tangent-based rotation search and least-squares matcher of F. Lu and E. Milios, "Robot
// pose estimation in unknown environments by matching 2D range scans", Journal of Intelligent
// and Robotic Systems 18, 1997 (also CVPR 1994), Sec. 3.
//
// Equation numbers are this file's; docs/methods/idc.md maps them to the paper and the functions.
//
// Every point gets a tangent line from a total least squares fit over its neighbours along the
// scan (normal n, tangent direction a = angle of the tangent, modulo pi). Matching then runs in
// two stages:
// 1. Rotation search over the tangent directions: a rotation w turns every source tangent by w,
//    so the histograms h_t, h_s of tangent directions (modulo pi, Gaussian-smoothed) correlate
//    best at the rotation:
//      w_0 = w_guess + argmax_{|d| <= max_rotation} sum_b h_t(b) h_s(b - w_guess - d)        Eq. (1)
//    (refined between bins by a parabola through the peak). The translation of the guess is kept,
//    the source turned about its sensor.
// 2. Least squares with the tangent lines, iterated: each source point m = T p pairs with the
//    nearest target point q within D(k) whose tangent agrees with m's turned tangent within
//    max_tangent_difference; for a rotation w the distance of the points to the tangent lines
//      E(w, t) = sum_i (n_i^T (R(w) p_i + t - q_i))^2                                       Eq. (2)
//    is quadratic in t, so t(w) = argmin_t E(w, t) in closed form (2x2 normal equations,
//    Eq. (3)) and the rotation is a one-dimensional search of E(w, t(w)) over
//    [w - rotation_search_width, w + rotation_search_width] (golden section, Eq. (4)).
//    The threshold D(k) shrinks as in idc.hpp, Eq. (6).
//
// The MatchResult is complete: the final pairs (point-to-line along the target's fitted normals,
// the metric of Eq. (2)) give the inliers, the residual (RMS of Eq. (2)'s terms), the covariance
// (censi_covariance, kPointToLine) and the degeneracy verdict.

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct TangentSearchConfig {
  int tangent_neighbors = 7;              // 1, points of each tangent line fit along the scan (itself included), >= 3
  double tangent_max_distance = 0.5;      // m, neighbours farther from the point are left out of its fit, > 0
  int histogram_bins = 180;               // 1, bins of the tangent-direction histograms over pi, >= 8
  double histogram_sigma = 0.02;          // rad, Gaussian smoothing of the histograms, > 0
  double max_rotation = 0.7;              // rad, the rotation search of Eq. (1) spans w_guess +- this, [0, pi/2)
  int max_iterations = 30;                // 1, least-squares iterations, >= 1
  double max_distance_initial = 1.0;      // m, pairing threshold D(0), > 0
  double max_distance_final = 0.2;        // m, its floor, in (0, max_distance_initial]
  double max_distance_decay = 0.15;       // 1/iteration, alpha of D(k) = max(D_final, D(0) exp(-alpha k)), >= 0
  double max_tangent_difference = 0.3;    // rad, paired points' tangents differ at most this (modulo pi), in (0, pi/2]
  double rotation_search_width = 0.05;    // rad, half-width of the per-iteration search of Eq. (4), > 0
  double translation_tolerance = 1e-4;    // m, converged when a step moves the source sensor less, >= 0
  double rotation_tolerance = 1e-5;       // rad, and turns it less, >= 0
  int min_correspondences = 6;            // 1, fewer pairs end the match unconverged, >= 3
  double range_sigma = 0.01;              // m, range noise for the covariance, > 0
};

/// Throws Error naming the first invalid field.
void validate(const TangentSearchConfig& config);

/// Reads the fields of a preset under their own names (for the matcher registry).
void read_fields(const ConfigNode& node, TangentSearchConfig& config);

/// Lu & Milios Sec. 3: rotation from the tangent directions, translation by least squares.
MatchResult match_tangent_search(const PointCloud2& target, const PointCloud2& source,
                                 const SE2& T_target_source_guess, const TangentSearchConfig& config = {});

/// Eq. (1) alone: the rotation (rad, within guess_rotation +- max_rotation) at which the
/// tangent-direction histograms of the two clouds (which must carry normals) agree best.
double tangent_histogram_rotation(const PointCloud2& target, const PointCloud2& source, double guess_rotation,
                                  const TangentSearchConfig& config = {});

}  // namespace slam2d
