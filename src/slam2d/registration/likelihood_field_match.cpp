// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/likelihood_field_match.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "slam2d/optim/levenberg_marquardt.hpp"
#include "slam2d/registration/degeneracy.hpp"

namespace slam2d {

namespace {

// The likelihood field's least squares for the driver (optim/levenberg_marquardt.hpp):
// residuals d(T p_i) of the points within outlier_distance, accepted on the truncated cost.
struct LikelihoodFieldCost {
  const LikelihoodField& field;
  const std::vector<Eigen::Vector2d>& points;
  const LikelihoodFieldMatchConfig& config;

  // J = dd/d(x, y, theta) = grad d [I, R' p] and r = d of every point within outlier_distance.
  NormalEquations<3> linearize(const Eigen::Vector3d& x) const {
    const SE2 T = SE2::from_vector(x);
    const double c = std::cos(T.theta());
    const double s = std::sin(T.theta());
    NormalEquations<3> equations;
    for (const Eigen::Vector2d& p : points) {
      Eigen::Vector2d gradient;
      const double d = field.distance(T.act(p), &gradient);
      if (!(d <= config.outlier_distance)) continue;
      const Eigen::Vector2d dq_dtheta(-s * p.x() - c * p.y(), c * p.x() - s * p.y());  // R' p
      equations.add(NormalEquations<3>::Row(gradient.x(), gradient.y(), gradient.dot(dq_dtheta)), d);
    }
    return equations;
  }
  // The truncated cost sum_i min(d_i, outlier_distance)^2: continuous when points cross the cut.
  double cost(const Eigen::Vector3d& x) const {
    const SE2 T = SE2::from_vector(x);
    double cost = 0.0;
    for (const Eigen::Vector2d& p : points) {
      const double d = std::min(field.distance(T.act(p)), config.outlier_distance);
      cost += d * d;
    }
    return cost;
  }
  Eigen::Vector3d plus(const Eigen::Vector3d& x, const Eigen::Vector3d& dx) const { return pose_plus(x, dx); }
};

// Levenberg-Marquardt with Marquardt's damping lambda (diag(H) + 1e-9), lambda from 1e-4, x 1/4
// down to 1e-7 on an accepted step, x 8 on a rejected one; stop on a small step or < 3 points.
LevenbergMarquardtConfig levenberg_marquardt_options(const LikelihoodFieldMatchConfig& config) {
  return {.max_iterations = config.max_iterations,
          .initial_lambda = 1e-4,
          .lambda_up = 8.0,
          .lambda_down = 0.25,
          .min_lambda = 1e-7,
          .diagonal_epsilon = 1e-9,
          .singular_pivot = 0.0,
          .min_residuals = 3,
          .step_translation = config.epsilon_xy,
          .step_rotation = config.epsilon_theta};
}

// The end points within inlier_distance of an obstacle at T (over all points: the EKF's gate).
std::size_t count_inliers(const LikelihoodField& field, const std::vector<Eigen::Vector2d>& points, const SE2& T,
                          double inlier_distance) {
  std::size_t inliers = 0;
  for (const Eigen::Vector2d& p : points) {
    if (field.distance(T.act(p)) <= inlier_distance) ++inliers;
  }
  return inliers;
}

}  // namespace

MatchResult match_likelihood_field(const LikelihoodField& field, const std::vector<Eigen::Vector2d>& points_robot,
                                   const SE2& T_map_robot_guess, const LikelihoodFieldMatchConfig& config) {
  MatchResult result;
  result.T_target_source = T_map_robot_guess;
  if (points_robot.size() < 3) return result;
  LikelihoodFieldCost cost{field, points_robot, config};
  const LevenbergMarquardtResult<3> fit =
      levenberg_marquardt<3>(cost, T_map_robot_guess.vector(), levenberg_marquardt_options(config));
  result.iterations = fit.iterations;
  if (fit.stop == LevenbergMarquardtStop::kNoStep || fit.stop == LevenbergMarquardtStop::kTooFewResiduals) {
    return result;  // the guess, not converged
  }
  const NormalEquations<3>& eq = fit.equations;
  result.T_target_source = SE2::from_vector(fit.x);
  result.converged = fit.converged;
  result.residual = std::sqrt(2.0 * eq.cost / static_cast<double>(eq.residuals));
  result.cost = eq.cost;
  result.inliers = count_inliers(field, points_robot, result.T_target_source, config.inlier_distance);
  result.inlier_fraction = static_cast<double>(result.inliers) / static_cast<double>(points_robot.size());
  const double sigma = std::max(config.sigma, result.residual);
  Eigen::Matrix3d H = eq.H;
  H.diagonal().array() += 1e-9;
  result.covariance = make_positive_definite(sigma * sigma * H.inverse(), 1e-10);
  // The degeneracy verdict on the scan's information (registration/degeneracy.hpp), rotation
  // scaled at the points' RMS distance; the covariance above already shows the weak direction.
  double squared_radius = 0.0;
  for (const Eigen::Vector2d& p : points_robot) squared_radius += p.squaredNorm();
  const DegeneracyAnalysis analysis =
      analyze_information(eq.H, std::sqrt(squared_radius / static_cast<double>(points_robot.size())), config.degeneracy);
  result.degenerate = analysis.degenerate;
  result.weak_direction = analysis.weak_direction;
  result.information_eigenvalues = analysis.eigenvalues;
  return result;
}

}  // namespace slam2d
