#include "slam2d/registration/likelihood_field_match.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "slam2d/registration/degeneracy.hpp"

namespace slam2d {

namespace {

struct NormalEquations {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double squared = 0.0;
  int used = 0;
  int inliers = 0;
};

// J^T J and J^T r of the distances at pose T (Gauss-Newton linearisation in (x, y, theta)).
NormalEquations linearize(const LikelihoodField& field, const std::vector<Eigen::Vector2d>& points, const SE2& T,
                          const LikelihoodFieldMatchConfig& config) {
  NormalEquations eq;
  const double c = std::cos(T.theta());
  const double s = std::sin(T.theta());
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2d q = T.act(p);
    Eigen::Vector2d gradient;
    const double d = field.distance(q, &gradient);
    if (d <= config.inlier_distance) ++eq.inliers;
    if (!(d <= config.outlier_distance)) continue;
    // d(q)/d(theta) = R' p.
    const Eigen::Vector2d dq_dtheta(-s * p.x() - c * p.y(), c * p.x() - s * p.y());
    const Eigen::Vector3d J(gradient.x(), gradient.y(), gradient.dot(dq_dtheta));
    eq.H += J * J.transpose();
    eq.b += J * d;
    eq.squared += d * d;
    ++eq.used;
  }
  return eq;
}

// The truncated cost sum_i min(d_i, outlier_distance)^2: continuous when points cross the cut.
double truncated_cost(const LikelihoodField& field, const std::vector<Eigen::Vector2d>& points, const SE2& T,
                      const LikelihoodFieldMatchConfig& config) {
  double cost = 0.0;
  for (const Eigen::Vector2d& p : points) {
    const double d = std::min(field.distance(T.act(p)), config.outlier_distance);
    cost += d * d;
  }
  return cost;
}

}  // namespace

MatchResult match_likelihood_field(const LikelihoodField& field, const std::vector<Eigen::Vector2d>& points_robot,
                                   const SE2& T_map_robot_guess, const LikelihoodFieldMatchConfig& config) {
  MatchResult result;
  result.T_target_source = T_map_robot_guess;
  if (points_robot.size() < 3) return result;
  SE2 T = T_map_robot_guess;
  double cost = truncated_cost(field, points_robot, T, config);
  double lambda = -1.0;  // Levenberg-Marquardt damping, relative to diag(H)
  NormalEquations eq = linearize(field, points_robot, T, config);
  for (int iteration = 0; iteration < config.max_iterations; ++iteration) {
    result.iterations = iteration + 1;
    if (eq.used < 3) return result;
    if (lambda < 0.0) lambda = 1e-4;
    Eigen::Matrix3d A = eq.H;
    A.diagonal() += lambda * (eq.H.diagonal().array() + 1e-9).matrix();
    const Eigen::Vector3d step = -A.ldlt().solve(eq.b);
    if (!step.allFinite()) return result;
    const SE2 candidate(T.x() + step.x(), T.y() + step.y(), T.theta() + step.z());
    const double candidate_cost = truncated_cost(field, points_robot, candidate, config);
    const bool small = std::hypot(step.x(), step.y()) < config.epsilon_xy && std::abs(step.z()) < config.epsilon_theta;
    if (candidate_cost <= cost) {
      T = candidate;
      cost = candidate_cost;
      lambda = std::max(lambda / 4.0, 1e-7);
      if (small) {
        result.converged = true;
        break;
      }
      eq = linearize(field, points_robot, T, config);
    } else {
      // No decrease: damp harder; a step that small cannot improve, so T is the minimum.
      if (small) {
        result.converged = true;
        break;
      }
      lambda *= 8.0;
    }
  }
  eq = linearize(field, points_robot, T, config);
  if (eq.used < 3) {
    result.converged = false;
    return result;
  }
  result.T_target_source = T;
  result.residual = std::sqrt(eq.squared / eq.used);
  result.inliers = static_cast<std::size_t>(eq.inliers);
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
  return result;
}

}  // namespace slam2d
