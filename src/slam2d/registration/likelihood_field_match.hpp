// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scan-to-map matching against a likelihood field (the EKF's measurement, the localizers' motion
// within an odometry stall): the pose that minimises the squared distances
// of the scan's end points to the nearest obstacle of the map,
//   T* = argmin_T sum_i d(T p_i)^2,
// with d the likelihood field's distance (grid/likelihood_field.hpp: exact EDT, bilinear, with
// its exact gradient), by Levenberg-Marquardt from the predicted pose (the shared driver,
// optim/levenberg_marquardt.hpp, on the cost LikelihoodFieldCost: a step is taken only if it
// lowers the truncated cost sum min(d, outlier_distance)^2, else the damping grows; converged when
// the step falls below epsilon): the point-to-distance-field form
// of ICP against the map's points (A. Fitzgibbon, "Robust registration of 2D and 3D point sets",
// 2003; the distance map replaces the nearest-neighbour search). Points farther than
// outlier_distance from any obstacle are left out (unmapped objects, glass).
//
// The covariance is sigma^2 (J^T J)^-1 at the optimum (the Hessian approximation, as Hector's
// and Censi's covariance-from-Hessian), with sigma the larger of config.sigma and the RMS
// residual, so a poor fit widens it. MatchResult::inliers counts the end points within
// inlier_distance of an obstacle after the match (over all points: the EKF's gate;
// inlier_fraction = inliers / points), cost is sum d^2 / 2 of the points used, and
// degenerate / weak_direction say whether the fit's information J^T J constrains every direction
// (a corridor's axis does not; registration/degeneracy.hpp).

#include <Eigen/Core>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/likelihood_field.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct LikelihoodFieldMatchConfig {
  int max_iterations = 30;
  double outlier_distance = 0.5;
  double inlier_distance = 0.2;
  double sigma = 0.05;
  double epsilon_xy = 1e-3;
  double epsilon_theta = 1e-3;
  DegeneracyConfig degeneracy{};
};

template <typename Fields>
void describe(Fields& f, LikelihoodFieldMatchConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "");
  f.number("outlier_distance", c.outlier_distance, "m", greater_than(0), "points farther from an obstacle do not count");
  f.number("inlier_distance", c.inlier_distance, "m", greater_than(0), "points this close after the match are inliers");
  f.number("sigma", c.sigma, "m", greater_than(0), "floor of the per-point residual sigma of the covariance");
  f.number("epsilon_xy", c.epsilon_xy, "m", at_least(0), "stop when the step is below this ...");
  f.number("epsilon_theta", c.epsilon_theta, "rad", at_least(0), "... and this");
  f.section("degeneracy", c.degeneracy, "the verdict on the fit's information (MatchResult::degenerate)");
}

/// T_target_source is T_map_robot (the guess when the match fails); converged: the step became
/// small with >= 3 points; residual: the RMS distance of the points used (m).
MatchResult match_likelihood_field(const LikelihoodField& field, const std::vector<Eigen::Vector2d>& points_robot,
                                   const SE2& T_map_robot_guess, const LikelihoodFieldMatchConfig& config = {});

}  // namespace slam2d
