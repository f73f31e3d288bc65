// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The improved proposal of G. Grisetti, C. Stachniss, W. Burgard, "Improved techniques for grid
// mapping with Rao-Blackwellized particle filters", IEEE T-RO 23(1), 2007, Sec. IV-A (GMapping).
//
// For one particle with pose x_{t-1} and map m, given the odometry motion u and the scan z:
//   x' = x_{t-1} (+) u                                 prediction (the odometry motion model's mode)
//   x* = argmax_x p(z | m, x)                          scan matching from x' (Hector's matcher,
//                                                      registration/occupancy_gradient_match.hpp)
//   x_j = x* (+) v_j, j = 1..K                          a fixed grid of K poses around x*
//   tau_j = p(z | m, x_j) p(x_j | x_{t-1}, u)           Eq. (14)-(15): likelihood times motion model
//   eta = sum_j tau_j                                   Eq. (18): the proposal's normaliser
//   mu = (1 / eta) sum_j x_j tau_j                      Eq. (16)
//   Sigma = (1 / eta) sum_j tau_j (x_j - mu)(x_j - mu)^T  Eq. (17)
// The new pose is drawn from N(mu, Sigma) and the weight is multiplied by eta (times the grid's
// cell volume, so that it is comparable with the motion-model fallback's weight p(z | m, x)).
// Poses x_j, mu and Sigma are expressed in the local frame of x* (tangent coordinates).
//
// Observation likelihood: the Hector map value M in [0, 1] (bilinear occupancy, grid/bilinear.hpp)
// at each end point, log p(z | m, x) = -sum_i (1 - M(S_i(x)))^2 / (2 sigma^2), i.e. Hector's
// matching cost read as a Gaussian on the residual 1 - M.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "slam2d/core/rng.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/map_pyramid.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/registration/occupancy_gradient_match.hpp"

namespace slam2d {

/// Odometry motion noise (standard deviations growing with the motion, as GMapping's srr, srt,
/// str, stt), in the frame of the predicted pose.
struct RbpfMotionNoise {
  double srr = 0.1;
  double srt = 0.1;
  double str = 0.1;
  double stt = 0.2;
  double min_sigma_translation = 0.01;
  double min_sigma_rotation = 0.005;
  // The particles' spread in one update (update_sigmas), capped. The noise of one update is linear
  // in its motion, which across a gap in the scans (the robot drove tens of metres unseen: the
  // odometry's increment is one step) spreads the particles' starts over metres and radians, far
  // beyond the matcher's reach: the particle that wins is a draw and the map goes on from its
  // heading (ACES with 198 s of scans missing and exact odometry: 0.96 m over all relations, the
  // odometry 0.039 m). Capped at the noise of a 2 m step, the particles spread around the
  // scan-matched odometry as after any long step. The per-scan matching's prior keeps the model's
  // sigmas (a long step's prior is weak: the scan decides). Of the three public logs, clean, one
  // update reaches the cap (ACES's 3 s gap, turning 0.94 rad: 0.202 -> 0.2 rad; the run the same
  // to 0.1 mm); turns of a radian between two updates do (a 1 Hz scan rate, the odometry out of
  // step on Intel). Chosen on ACES and Intel with a gap at 300 s, checked on FR079, a gap at 700 s
  // and the wheel odometry across the gap (docs/methods/rbpf.md, "Across a gap in the scans").
  double max_sigma_translation = 0.2;
  double max_sigma_rotation = 0.2;
};

template <typename Fields>
void describe(Fields& f, RbpfMotionNoise& c) {
  f.number("srr", c.srr, "m per m driven", at_least(0), "translation noise from translation");
  f.number("srt", c.srt, "m per rad turned", at_least(0), "translation noise from rotation");
  f.number("str", c.str, "rad per m driven", at_least(0), "rotation noise from translation");
  f.number("stt", c.stt, "rad per rad turned", at_least(0), "rotation noise from rotation");
  f.number("min_sigma_translation", c.min_sigma_translation, "m", greater_than(0), "floor of the translation sigma");
  f.number("min_sigma_rotation", c.min_sigma_rotation, "rad", greater_than(0), "floor of the rotation sigma");
  f.number("max_sigma_translation", c.max_sigma_translation, "m", greater_than(0), "cap of an update's translation spread (a long step: a gap in the scans)");
  f.number("max_sigma_rotation", c.max_sigma_rotation, "rad", greater_than(0), "cap of an update's rotation spread");
}

struct RbpfProposalConfig {
  // No multi-start; a corridor's open translation stays with the prediction (docs/defaults.md).
  HectorMatcherConfig matcher{.rotation_search_range = 0.0, .scan_degeneracy_ratio = 0.01};
  // Picked on ACES, not yet checked on a held-out log (docs/defaults.md), as are weight_gain and
  // the K poses' grid.
  double likelihood_sigma = 0.3;
  // Weight tempering (GMapping's "ogain"): the weight update is log eta * weight_gain. Beams are
  // not independent, so the product over ~200 beams is far too confident; 1 is the plain filter.
  double weight_gain = 0.03;
  // The motion model as a Gaussian prior in the scan matching (x* maximises likelihood times
  // motion model, the proposal's mode); 0 matches on the likelihood alone, 1 is the exact product.
  double motion_prior_weight = 1.0;
  // On the motion prior's Mahalanobis distance (occupancy_gradient_match.hpp's PosePrior); kNone
  // keeps the plain Gaussian of the paper.
  RobustKernel motion_prior_kernel{};
  std::size_t likelihood_stride = 2;
  int sample_radius = 1;
  double sample_step_translation = 0.02;
  double sample_step_rotation = 0.01;
  // The match is rejected (motion-model fallback) when its mean squared residual (1 - M)^2 exceeds
  // max_match_residual, when it moved the pose further than the gates from x', or when it is
  // degenerate.
  double max_match_residual = 0.5;
  double max_match_translation = 1.0;
  double max_match_rotation = 0.6;
  std::size_t min_points = 20;
};

template <typename Fields>
void describe(Fields& f, RbpfProposalConfig& c) {
  f.section("matcher", c.matcher, "scan matching from x'");
  f.number("likelihood_sigma", c.likelihood_sigma, "1", greater_than(0),
           "sigma of the residual 1 - M in the observation likelihood");
  f.number("weight_gain", c.weight_gain, "1", open_closed(0, 1), "the weight update is log eta * weight_gain");
  f.number("motion_prior_weight", c.motion_prior_weight, "1", at_least(0),
           "weight of the motion model as a prior in the scan matching (0: off, 1: the exact product)");
  f.section("motion_prior_kernel", c.motion_prior_kernel, "on the motion prior's Mahalanobis distance (none: Gaussian)");
  f.number("likelihood_stride", c.likelihood_stride, "1", at_least(1),
           "the K poses' likelihood reads every n-th end point (scaled to all of them)");
  f.number("sample_radius", c.sample_radius, "1", between(1, 5), "K = (2 radius + 1)^3 poses around x*");
  f.number("sample_step_translation", c.sample_step_translation, "m", greater_than(0), "grid step of the x_j in x and y");
  f.number("sample_step_rotation", c.sample_step_rotation, "rad", greater_than(0), "grid step of the x_j in theta");
  f.number("max_match_residual", c.max_match_residual, "1", open_closed(0, 1),
           "a match with a larger mean squared residual is rejected");
  f.number("max_match_translation", c.max_match_translation, "m", greater_than(0), "a match moving the pose farther is rejected");
  f.number("max_match_rotation", c.max_match_rotation, "rad", greater_than(0), "... or turning it more");
  f.number("min_points", c.min_points, "1", any_value(), "end points needed to match");
}

/// Throws Error for settings outside the documented ranges.
void validate(const RbpfMotionNoise& noise);
void validate(const RbpfProposalConfig& config);

/// The standard deviations (x, y, theta) of the motion noise for the robot-frame motion u.
Eigen::Vector3d motion_sigmas(const SE2& u, const RbpfMotionNoise& noise);

/// The same, at most the caps (max_sigma_translation, max_sigma_rotation): the particles' spread in
/// an update over the motion u.
Eigen::Vector3d update_sigmas(const SE2& u, const RbpfMotionNoise& noise);

/// log p(x | x', sigmas): the motion model's Gaussian density at x around the prediction x' (the
/// difference taken in the frame of x'), with its normalising constant.
double log_motion_density(const SE2& x, const SE2& predicted, const Eigen::Vector3d& sigmas);

/// log p(z | m, x) = -sum_i (1 - M(x p_i))^2 / (2 sigma^2) over robot-frame end points p_i.
/// With stride > 1 only every stride-th point is read and the sum is scaled by (points / points read).
double log_observation_likelihood(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                                  const SE2& T_map_robot, double sigma, std::size_t stride = 1);

struct ProposalResult {
  SE2 x_star;                          // the match (x' when it was rejected)
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();    // mu in the frame of x_star (tangent coordinates)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // Sigma, same frame
  double log_normalizer = 0.0;         // log(eta * cell volume)
  bool matched = false;                // false: use the motion model (fallback)
  // The scan match's covariance at x* (map frame; Hector's s^2 H^-1, the motion prior's
  // information in it); unknown unless matched.
  Covariance3 match_covariance = unknown_covariance();
};

/// Scan matching and the Gaussian fit of Eq. (14)-(18). An empty map (no scan yet) or a rejected
/// match gives matched = false. With fit = false only x* is computed (mean and covariance zero).
ProposalResult improved_proposal(const MapPyramid& map, const std::vector<Eigen::Vector2d>& points_robot,
                                 const SE2& predicted, const Eigen::Vector3d& sigmas, const RbpfProposalConfig& config,
                                 bool fit = true);

/// The pose the proposal expects: its mean mu (x* (+) mu), or x' when the match was rejected
/// (the motion model's mode). What sample_pose draws around, without the draw's noise.
SE2 proposal_mean(const ProposalResult& proposal, const SE2& predicted);

/// A pose drawn from the proposal: N(mu, Sigma) around x*, or the motion model around x' when
/// the match was rejected. `log_weight_factor` receives the weight update (log eta, or the
/// observation log likelihood at the drawn pose for the fallback).
SE2 sample_pose(const ProposalResult& proposal, const MapPyramid& map, const std::vector<Eigen::Vector2d>& points_robot,
                const SE2& predicted, const Eigen::Vector3d& sigmas, const RbpfProposalConfig& config, Rng& rng,
                double& log_weight_factor);

}  // namespace slam2d
