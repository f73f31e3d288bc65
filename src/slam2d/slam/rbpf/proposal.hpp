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
  double srr = 0.1;                     // m per m driven: translation noise from translation
  double srt = 0.1;                     // m per rad turned: translation noise from rotation
  double str = 0.1;                     // rad per m driven: rotation noise from translation
  double stt = 0.2;                     // rad per rad turned: rotation noise from rotation
  double min_sigma_translation = 0.01;  // m, floor (> 0)
  double min_sigma_rotation = 0.005;    // rad, floor (> 0)
};

struct RbpfProposalConfig {
  HectorMatcherConfig matcher{.rotation_search_range = 0.0};  // scan matching from x' (no multi-start)
  // 1, sigma of the residual 1 - M in the observation likelihood, > 0. Picked on ACES, not yet
  // checked on a held-out log (docs/defaults.md), as are weight_gain and the K poses' grid.
  double likelihood_sigma = 0.3;
  // Weight tempering (GMapping's "ogain"): the weight update is log eta * weight_gain. Beams are
  // not independent, so the product over ~200 beams is far too confident; 1 is the plain filter.
  double weight_gain = 0.03;          // 1, in (0, 1]
  // The motion model as a Gaussian prior in the scan matching (x* maximises likelihood times
  // motion model, the proposal's mode); 0 matches on the likelihood alone, 1 is the exact product.
  double motion_prior_weight = 1.0;   // 1, >= 0
  // The likelihood of the K poses reads every likelihood_stride-th end point (scaled to all of them).
  std::size_t likelihood_stride = 2;  // >= 1
  int sample_radius = 1;              // K = (2 radius + 1)^3 poses around x*, in [1, 5]
  double sample_step_translation = 0.02;  // m, grid step of the x_j in x and y, > 0
  double sample_step_rotation = 0.01;     // rad, grid step of the x_j in theta, > 0
  // The match is rejected (motion-model fallback) when its mean squared residual (1 - M)^2 exceeds
  // this, when it moved the pose further than the gates from x', or when it is degenerate.
  double max_match_residual = 0.5;    // 1, in (0, 1]
  double max_match_translation = 1.0; // m, > 0
  double max_match_rotation = 0.6;    // rad, > 0
  std::size_t min_points = 20;        // end points needed to match
};

/// Throws Error for settings outside the documented ranges.
void validate(const RbpfMotionNoise& noise);
void validate(const RbpfProposalConfig& config);

/// The standard deviations (x, y, theta) of the motion noise for the robot-frame motion u.
Eigen::Vector3d motion_sigmas(const SE2& u, const RbpfMotionNoise& noise);

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
};

/// Scan matching and the Gaussian fit of Eq. (14)-(18). An empty map (no scan yet) or a rejected
/// match gives matched = false. With fit = false only x* is computed (mean and covariance zero).
ProposalResult improved_proposal(const MapPyramid& map, const std::vector<Eigen::Vector2d>& points_robot,
                                 const SE2& predicted, const Eigen::Vector3d& sigmas, const RbpfProposalConfig& config,
                                 bool fit = true);

/// A pose drawn from the proposal: N(mu, Sigma) around x*, or the motion model around x' when
/// the match was rejected. `log_weight_factor` receives the weight update (log eta, or the
/// observation log likelihood at the drawn pose for the fallback).
SE2 sample_pose(const ProposalResult& proposal, const MapPyramid& map, const std::vector<Eigen::Vector2d>& points_robot,
                const SE2& predicted, const Eigen::Vector3d& sigmas, const RbpfProposalConfig& config, Rng& rng,
                double& log_weight_factor);

}  // namespace slam2d
