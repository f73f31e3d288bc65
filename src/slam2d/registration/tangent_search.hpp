// SPDX-License-Identifier: BSD-3-Clause
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

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct TangentSearchConfig {
  int tangent_neighbors = 7;
  double tangent_max_distance = 0.5;
  int histogram_bins = 180;
  double histogram_sigma = 0.02;
  double max_rotation = 0.7;
  int max_iterations = 30;
  double max_distance_initial = 1.0;
  double max_distance_final = 0.2;
  double max_distance_decay = 0.15;
  double max_tangent_difference = 0.3;
  double rotation_search_width = 0.05;
  double translation_tolerance = 1e-4;
  double rotation_tolerance = 1e-5;
  int min_correspondences = 6;
  double range_sigma = 0.01;
};

template <typename Fields>
void describe(Fields& f, TangentSearchConfig& c) {
  f.number("tangent_neighbors", c.tangent_neighbors, "1", at_least(3), "points of each tangent line fit along the scan (itself included)");
  f.number("tangent_max_distance", c.tangent_max_distance, "m", greater_than(0), "neighbours farther from the point are left out of its fit");
  f.number("histogram_bins", c.histogram_bins, "1", at_least(8), "bins of the tangent-direction histograms over pi");
  f.number("histogram_sigma", c.histogram_sigma, "rad", greater_than(0), "Gaussian smoothing of the histograms");
  f.number("max_rotation", c.max_rotation, "rad", closed_open(0, std::numbers::pi / 2), "the rotation search of Eq. (1) spans w_guess +- this");
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "least-squares iterations");
  f.number("max_distance_initial", c.max_distance_initial, "m", greater_than(0), "pairing threshold D(0)");
  f.number("max_distance_final", c.max_distance_final, "m", greater_than(0), "its floor, <= max_distance_initial");
  f.number("max_distance_decay", c.max_distance_decay, "1/iteration", at_least(0), "alpha of D(k) = max(D_final, D(0) exp(-alpha k))");
  f.number("max_tangent_difference", c.max_tangent_difference, "rad", open_closed(0, std::numbers::pi / 2), "paired points' tangents differ at most this (modulo pi)");
  f.number("rotation_search_width", c.rotation_search_width, "rad", greater_than(0), "half-width of the per-iteration search of Eq. (4)");
  f.number("translation_tolerance", c.translation_tolerance, "m", at_least(0), "converged when a step moves the source sensor less ...");
  f.number("rotation_tolerance", c.rotation_tolerance, "rad", at_least(0), "... and turns it less");
  f.number("min_correspondences", c.min_correspondences, "1", at_least(3), "fewer pairs end the match unconverged");
  f.number("range_sigma", c.range_sigma, "m", greater_than(0), "range noise for the covariance");
}

/// Throws Error naming the first invalid field.
void validate(const TangentSearchConfig& config);


/// Lu & Milios Sec. 3: rotation from the tangent directions, translation by least squares.
MatchResult match_tangent_search(const PointCloud2& target, const PointCloud2& source,
                                 const SE2& T_target_source_guess, const TangentSearchConfig& config = {});

/// Eq. (1) alone: the rotation (rad, within guess_rotation +- max_rotation) at which the
/// tangent-direction histograms of the two clouds (which must carry normals) agree best.
double tangent_histogram_rotation(const PointCloud2& target, const PointCloud2& source, double guess_rotation,
                                  const TangentSearchConfig& config = {});

}  // namespace slam2d
