// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/occupancy_gradient_match.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/grid/bilinear.hpp"
#include "slam2d/optim/levenberg_marquardt.hpp"
#include "slam2d/registration/degeneracy.hpp"

namespace slam2d {

void validate(const HectorMatcherConfig& config) {
  check_fields(config, "HectorMatcherConfig");
  check(config.rotation_search_range / config.rotation_search_step <= 100.0,
        "HectorMatcherConfig: more than 201 rotation search starts");
}

NormalEquations<3> hector_linearize(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                                    const SE2& T_map_robot, const RobustKernel& kernel) {
  const double c = std::cos(T_map_robot.theta());
  const double s = std::sin(T_map_robot.theta());
  const Eigen::Vector2d& t = T_map_robot.translation();
  NormalEquations<3> equations;
  OccupancyInterpolator interpolate(grid);  // interpolate_occupancy, bit for bit
  for (const Eigen::Vector2d& p : points_robot) {
    const Eigen::Vector2d S(c * p.x() - s * p.y() + t.x(), s * p.x() + c * p.y() + t.y());  // Eq. (7)
    const BilinearSample M = interpolate(S);
    const double r = 1.0 - M.value;
    // grad M * dS/dxi, Eq. (14): the rotation column is dS/dpsi = (-s p_x - c p_y, c p_x - s p_y).
    const double d_psi = M.gradient.x() * (-s * p.x() - c * p.y()) + M.gradient.y() * (c * p.x() - s * p.y());
    const NormalEquations<3>::Row J(-M.gradient.x(), -M.gradient.y(), -d_psi);  // dr/dxi
    equations.add(J, r, kernel.weight(r));
  }
  return equations;
}

namespace {

Eigen::Vector3d prior_residual(const SE2& T_map_robot, const PosePrior& prior) {
  Eigen::Vector3d r = T_map_robot.vector() - prior.mean.vector();
  r.z() = normalize_angle(r.z());
  return r;
}

}  // namespace

double prior_distance(const SE2& T_map_robot, const PosePrior& prior) {
  const Eigen::Vector3d r = prior_residual(T_map_robot, prior);
  return std::sqrt(r.dot(prior.information * r));
}

void add_pose_prior(NormalEquations<3>& equations, const SE2& T_map_robot, const PosePrior& prior) {
  const Eigen::Vector3d r = prior_residual(T_map_robot, prior);
  const double distance = prior_distance(T_map_robot, prior);
  const double weight = prior.kernel.weight(distance);
  equations.H += weight * prior.information;  // J = I
  equations.b += weight * prior.information * r;
  equations.cost += prior.kernel.cost(distance);
}

double explained_share(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot) {
  if (points_robot.empty()) return 0.0;
  OccupancyInterpolator interpolate(grid);
  std::size_t explained = 0;
  for (const Eigen::Vector2d& p : points_robot) {
    if (interpolate(T_map_robot * p).value > kExplainedOccupancy) ++explained;
  }
  return static_cast<double>(explained) / static_cast<double>(points_robot.size());
}

namespace {

// Solution remapping: the projector onto the eigenvectors of the information whose eigenvalue
// exceeds ratio times the largest (the directions the scan constrains).
Eigen::Matrix3d constrained_projector(const Eigen::Matrix3d& information, double ratio) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(information);
  const double largest = eigen.eigenvalues()(2);
  Eigen::Matrix3d projector = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d v = eigen.eigenvectors().col(k);
    if (eigen.eigenvalues()(k) > ratio * largest) projector += v * v.transpose();
  }
  return projector;
}

// The translation the scan's own geometry leaves open (HectorMatcherConfig::scan_degeneracy_ratio,
// registration/degeneracy.hpp's open_translation): steps lose their part along it, turned into the
// map frame.
class OpenTranslation {
 public:
  explicit OpenTranslation(const Eigen::Vector2d& direction_robot) : direction_robot_(direction_robot) {}
  Eigen::Vector3d remove_from(const Eigen::Vector3d& step, double heading) const {
    return without_translation_along(step, Eigen::Rotation2Dd(heading) * direction_robot_);
  }

 private:
  Eigen::Vector2d direction_robot_;
};

std::optional<OpenTranslation> open_translation_of(const std::vector<Eigen::Vector2d>& points_robot,
                                                   const HectorMatcherConfig& config) {
  const std::optional<Eigen::Vector2d> direction = scan_open_translation(points_robot, config);
  if (!direction) return std::nullopt;
  return OpenTranslation(*direction);
}

// The covariance s^2 H^-1 with s^2 = sum r^2 / (n - 3), the residual variance. When H is singular
// or there are too few points, the match says nothing: unknown_covariance(), never a zero one.
Covariance3 covariance_from_hessian(const NormalEquations<3>& equations) {
  const auto inverse = inverse_hessian(equations);
  if (!inverse || equations.residuals <= 3) return unknown_covariance();
  const double variance = 2.0 * equations.cost / static_cast<double>(equations.residuals - 3);
  return variance * *inverse;
}

// The least constrained direction of the scan's own information (H without the prior) at the
// estimate (registration/degeneracy.hpp, rotation scaled at the points' RMS distance).
Eigen::Vector3d weakest_direction(const NormalEquations<3>& equations, const SE2& T_map_robot,
                                  const std::vector<Eigen::Vector2d>& points_robot, const std::optional<PosePrior>& prior) {
  Eigen::Matrix3d scan_information = equations.H;
  if (prior) {
    NormalEquations<3> prior_only;
    add_pose_prior(prior_only, T_map_robot, *prior);
    scan_information -= prior_only.H;
  }
  double squared_radius = 0.0;
  for (const Eigen::Vector2d& p : points_robot) squared_radius += p.squaredNorm();
  const double radius = std::sqrt(squared_radius / static_cast<double>(std::max<std::size_t>(points_robot.size(), 1)));
  return analyze_information(scan_information, radius > 0.0 ? radius : 1.0).weak_direction;
}

// Hector's Gauss-Newton problem on one grid for the driver (optim/levenberg_marquardt.hpp):
// Eq. (12)-(14) plus the optional pose prior, and the step shaping (solution remapping, clamps).
struct HectorCost {
  const OccupancyGrid& grid;
  const std::vector<Eigen::Vector2d>& points_robot;
  const HectorMatcherConfig& config;
  const std::optional<PosePrior>& prior;
  const std::optional<OpenTranslation>& open;
  Eigen::Matrix3d scan_information = Eigen::Matrix3d::Zero();  // H of the scan alone, at the last linearisation
  double heading = 0.0;                                         // of the last linearisation

  NormalEquations<3> linearize(const Eigen::Vector3d& xi) {
    const SE2 pose = SE2::from_vector(xi);
    NormalEquations<3> equations = hector_linearize(grid, points_robot, pose, config.kernel);
    scan_information = equations.H;
    heading = pose.theta();
    if (prior) add_pose_prior(equations, pose, *prior);
    return equations;
  }
  Eigen::Vector3d plus(const Eigen::Vector3d& xi, const Eigen::Vector3d& dxi) const { return pose_plus(xi, dxi); }
  Eigen::Vector3d shape_step(Eigen::Vector3d dxi) const {
    if (config.degeneracy_ratio > 0.0) dxi = constrained_projector(scan_information, config.degeneracy_ratio) * dxi;
    if (open) dxi = open->remove_from(dxi, heading);
    dxi.z() = std::clamp(dxi.z(), -config.max_rotation_step, config.max_rotation_step);
    const double max_translation = config.max_translation_step * grid.geometry().resolution;
    if (dxi.head<2>().norm() > max_translation) dxi.head<2>() *= max_translation / dxi.head<2>().norm();
    return dxi;
  }
};

// The driver's options for Hector's loop: plain Gauss-Newton steps (Eq. 12), a step that raises
// the cost halved up to max_step_halvings times, else the level ends. A level stops when an
// accepted step is below 4 convergence_step (translation and rotation each): the threshold the
// loop has always applied (it tested half the accepted step against twice convergence_step).
LevenbergMarquardtConfig gauss_newton_options(const HectorMatcherConfig& config, int iterations) {
  return {.max_iterations = iterations,
          .initial_lambda = 0.0,
          .adapt = false,
          .max_step_halvings = config.max_step_halvings,
          .step_translation = 4.0 * config.convergence_step,
          .step_rotation = 4.0 * config.convergence_step};
}

// One Gauss-Newton run on one grid (the driver's fit: pose, last linearisation, iterations).
LevenbergMarquardtResult<3> fit_on_grid(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                                        const SE2& T_map_robot_guess, int iterations, const HectorMatcherConfig& config,
                                        const std::optional<PosePrior>& prior,
                                        const std::optional<OpenTranslation>& open) {
  HectorCost cost{grid, points_robot, config, prior, open};
  return levenberg_marquardt<3>(cost, T_map_robot_guess.vector(), gauss_newton_options(config, iterations));
}

// Whether a rotated start's fit may overrule the guess (HectorMatcherConfig::rotation_search_min_explained):
// within the prior kernel's scale it agrees with the prior; beyond it, only a fit that explains the scan.
bool may_overrule(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                  const LevenbergMarquardtResult<3>& fit, const HectorMatcherConfig& config,
                  const std::optional<PosePrior>& prior) {
  if (!prior || config.rotation_search_min_explained <= 0.0) return true;
  const SE2 pose = SE2::from_vector(fit.x);
  if (prior_distance(pose, *prior) <= prior->kernel.scale) return true;
  return explained_share(grid, points_robot, pose) >= config.rotation_search_min_explained;
}

// The multi-start of HectorMatcherConfig::rotation_search_range on one grid: the lowest final cost
// wins, a rotated start only by the margin and where it may_overrule the guess.
LevenbergMarquardtResult<3> fit_with_rotation_search(const OccupancyGrid& grid,
                                                     const std::vector<Eigen::Vector2d>& points_robot, const SE2& guess,
                                                     int iterations, const HectorMatcherConfig& config,
                                                     const std::optional<PosePrior>& prior,
                                                     const std::optional<OpenTranslation>& open) {
  LevenbergMarquardtResult<3> best = fit_on_grid(grid, points_robot, guess, iterations, config, prior, open);
  const int starts = static_cast<int>(std::floor(config.rotation_search_range / config.rotation_search_step + 1e-9));
  for (int k = -starts; k <= starts; ++k) {
    if (k == 0) continue;
    const SE2 start = guess * SE2(0.0, 0.0, k * config.rotation_search_step);
    LevenbergMarquardtResult<3> candidate = fit_on_grid(grid, points_robot, start, iterations, config, prior, open);
    // A rotated start must beat the current best clearly: in rotationally ambiguous places (a
    // round hall) near-equal costs would otherwise pick a far heading at random.
    if (candidate.equations.cost < (1.0 - config.rotation_search_margin) * best.equations.cost &&
        may_overrule(grid, points_robot, candidate, config, prior)) {
      best = std::move(candidate);
    }
  }
  return best;
}

// The match result of the finest fit: s^2 H^-1, the residuals, the scan's weakest direction.
MatchResult match_result(const LevenbergMarquardtResult<3>& fit, const std::vector<Eigen::Vector2d>& points_robot,
                         const std::optional<PosePrior>& prior) {
  MatchResult result;
  result.T_target_source = SE2::from_vector(fit.x);
  result.covariance = covariance_from_hessian(fit.equations);
  result.converged = fit.converged;
  result.degenerate = fit.stop == LevenbergMarquardtStop::kNoStep;
  result.iterations = fit.iterations;
  result.inliers = fit.equations.residuals;
  result.cost = fit.equations.cost;
  result.residual = std::sqrt(mean_squared_residual(result));
  result.weak_direction = weakest_direction(fit.equations, SE2::from_vector(fit.x), points_robot, prior);
  return result;
}

}  // namespace

MatchResult match_scan_to_grid(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                               const SE2& T_map_robot_guess, int iterations, const HectorMatcherConfig& config,
                               const std::optional<PosePrior>& prior) {
  return match_result(fit_on_grid(grid, points_robot, T_map_robot_guess, iterations, config, prior,
                                  open_translation_of(points_robot, config)),
                      points_robot, prior);
}

MatchResult match_scan_to_pyramid(const MapPyramid& pyramid, const std::vector<Eigen::Vector2d>& points_robot,
                                  const SE2& T_map_robot_guess, const HectorMatcherConfig& config,
                                  const std::optional<PosePrior>& prior) {
  validate(config);
  if (points_robot.size() < 3) {  // fewer points than the pose has degrees of freedom
    MatchResult result;
    result.T_target_source = T_map_robot_guess;
    result.degenerate = true;
    return result;
  }
  // Coarse to fine (Sec. IV-C): only the finest level's fit becomes the result (its covariance
  // and weak direction); the coarser ones only pass their pose on.
  const std::optional<OpenTranslation> open = open_translation_of(points_robot, config);
  Eigen::Vector3d pose = T_map_robot_guess.vector();
  int iterations = 0;
  for (int level = pyramid.levels() - 1; level >= 1; --level) {
    const SE2 start = SE2::from_vector(pose);
    const LevenbergMarquardtResult<3> coarse =
        level == pyramid.levels() - 1
            ? fit_with_rotation_search(pyramid.level(level), points_robot, start, config.coarse_iterations, config, prior, open)
            : fit_on_grid(pyramid.level(level), points_robot, start, config.coarse_iterations, config, prior, open);
    pose = coarse.x;
    iterations += coarse.iterations;
  }
  MatchResult fine = match_result(
      fit_on_grid(pyramid.level(0), points_robot, SE2::from_vector(pose), config.fine_iterations, config, prior, open),
      points_robot, prior);
  fine.iterations += iterations;
  return fine;
}

// The geometry of the last scan is kept per thread: the RBPF matches one scan once per particle
// and reads its open translation again for the proposal's fit.
std::optional<Eigen::Vector2d> scan_open_translation(const std::vector<Eigen::Vector2d>& points_robot,
                                                     const HectorMatcherConfig& config) {
  if (!(config.scan_degeneracy_ratio > 0.0)) return std::nullopt;
  thread_local std::vector<Eigen::Vector2d> last_points;
  thread_local ScanGeometry last_geometry = scan_geometry(last_points);
  if (points_robot != last_points) {
    last_geometry = scan_geometry(points_robot);
    last_points = points_robot;
  }
  return open_translation(last_geometry, config.scan_degeneracy_ratio);
}

}  // namespace slam2d
