// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The one Gauss-Newton / Levenberg-Marquardt driver over normal_equations.hpp (K. Levenberg 1944,
// D. W. Marquardt 1963; the lambda schedule of Numerical Recipes, 3rd ed., Sec. 15.5.2) that every
// least-squares matcher runs: linearise, solve the damped step (H + lambda (diag(H) + epsilon)) dx
// = -b, shape it (clamps, projections), halve it while it raises the cost, keep it when the cost
// does not rise (and relax lambda), else raise lambda and retry; stop when the step is small.
// With initial_lambda = 0 and adapt = false every step is a plain Gauss-Newton step.
//
// A problem is a small type (no virtual calls: the driver is a template) with
//   NormalEquations<N> linearize(const Vector& x);      residuals and Jacobian at x (required)
//   double cost(const Vector& x);                       the cost a step is accepted on (optional;
//                                                       default linearize(x).cost)
//   Vector plus(const Vector& x, const Vector& dx);     applies a step (optional; default x + dx,
//                                                       pose_plus for an SE2 pose)
//   Vector shape_step(const Vector& dx);                clamps or projects a solved step (optional)
// linearize and cost may keep state (the driver holds the problem by reference); shape_step is
// called right after the linearisation at the current x.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <type_traits>
#include <utility>

#include "slam2d/core/angles.hpp"
#include "slam2d/optim/normal_equations.hpp"

namespace slam2d {

struct LevenbergMarquardtConfig {
  int max_iterations = 20;         // linear systems solved, >= 1
  double initial_lambda = 1e-4;    // 1, damping of the first step (0: Gauss-Newton)
  double lambda_up = 10.0;         // 1, factor on a rejected step
  double lambda_down = 0.1;        // 1, factor on an accepted step ...
  double min_lambda = 0.0;         // 1, ... down to this floor
  double diagonal_epsilon = 0.0;   // added to diag(H) in the damping: lambda (diag(H) + epsilon) (kDiagonal)
  Damping damping = Damping::kDiagonal;
  bool adapt = true;               // false: lambda stays initial_lambda and a step that cannot lower the
                                   // cost (even halved) ends the run as converged
  int max_step_halvings = 0;       // a step that raises the cost is halved up to this often before it counts as rejected
  double singular_pivot = 1e-12;   // solve_step's singularity test (StepConfig); 0: only a non-finite step fails
  std::size_t min_residuals = 0;   // a linearisation with fewer residual blocks ends the run (kTooFewResiduals)
  // Converged when a step (the accepted one, or the rejected one: nothing shorter can help) is
  // shorter than min_step_norm; for a pose (N = 3: x, y, theta) with step_translation > 0 instead
  // when |dx_xy| < step_translation and |dx_theta| < step_rotation.
  double min_step_norm = 1e-10;    // 1 (units of x)
  double step_translation = 0.0;   // m, >= 0 (N = 3)
  double step_rotation = 0.0;      // rad, >= 0 (N = 3)
};

enum class LevenbergMarquardtStop {
  kMaxIterations,    // max_iterations systems solved
  kConverged,        // the step became small, or (adapt = false) no step lowered the cost
  kNoStep,           // the system was singular or gave a non-finite step: x is where that happened
  kTooFewResiduals,  // a linearisation had fewer than min_residuals blocks
};

template <int N>
struct LevenbergMarquardtResult {
  typename NormalEquations<N>::Vector x;
  NormalEquations<N> equations;  // linearised at x (H gives the covariance)
  int iterations = 0;            // linear systems solved (tried)
  bool converged = false;        // stop == kConverged
  double cost = 0.0;             // the acceptance cost at x
  LevenbergMarquardtStop stop = LevenbergMarquardtStop::kMaxIterations;
};

/// The step on a pose vector (x, y, theta): added, the angle normalised to [-pi, pi) as SE2 keeps it.
inline Eigen::Vector3d pose_plus(const Eigen::Vector3d& x, const Eigen::Vector3d& dx) {
  Eigen::Vector3d result = x + dx;
  result.z() = normalize_angle(result.z());
  return result;
}

namespace detail {

template <int N>
bool step_is_small(const typename NormalEquations<N>::Vector& dx, const LevenbergMarquardtConfig& config) {
  if constexpr (N == 3) {
    if (config.step_translation > 0.0) {
      return dx.template head<2>().norm() < config.step_translation && std::abs(dx.z()) < config.step_rotation;
    }
  }
  return dx.norm() < config.min_step_norm;
}

}  // namespace detail

/// Minimises the problem's cost from x0 (see the top of this file for what a problem provides).
template <int N, typename Problem>
  requires requires(Problem& p, const typename NormalEquations<N>::Vector& x) { p.linearize(x); }
LevenbergMarquardtResult<N> levenberg_marquardt(Problem& problem, const typename NormalEquations<N>::Vector& x0,
                                                const LevenbergMarquardtConfig& config = {}) {
  using Vector = typename NormalEquations<N>::Vector;
  constexpr bool kSeparateCost = requires(Problem& p, const Vector& x) { p.cost(x); };
  const auto cost_at = [&](const Vector& x, const NormalEquations<N>& equations) {
    if constexpr (kSeparateCost) {
      return problem.cost(x);
    } else {
      (void)x;
      return equations.cost;
    }
  };
  const auto plus = [&](const Vector& x, const Vector& dx) -> Vector {
    if constexpr (requires { problem.plus(x, dx); }) {
      return problem.plus(x, dx);
    } else {
      return x + dx;
    }
  };
  LevenbergMarquardtResult<N> result;
  result.x = x0;
  result.equations = problem.linearize(result.x);
  result.cost = cost_at(result.x, result.equations);
  bool linearized_at_x = true;
  double lambda = config.initial_lambda;
  const StepConfig step_config{.lambda = 0.0, .damping = config.damping, .epsilon = config.diagonal_epsilon,
                               .singular_pivot = config.singular_pivot};
  for (int iteration = 0; iteration < config.max_iterations; ++iteration) {
    result.iterations = iteration + 1;
    if (result.equations.residuals < config.min_residuals) {
      result.stop = LevenbergMarquardtStop::kTooFewResiduals;
      return result;
    }
    StepConfig damped = step_config;
    damped.lambda = lambda;
    const std::optional<Vector> solved = solve_step(result.equations, damped);
    if (!solved) {
      result.stop = LevenbergMarquardtStop::kNoStep;
      return result;
    }
    Vector dx = *solved;
    if constexpr (requires { problem.shape_step(dx); }) dx = problem.shape_step(dx);
    // Try the step, halved while it raises the cost (a Gauss-Newton step can overshoot).
    bool accepted = false;
    for (int halving = 0; halving <= config.max_step_halvings; ++halving) {
      if (halving > 0) dx *= 0.5;
      const Vector candidate = plus(result.x, dx);
      NormalEquations<N> candidate_equations;
      if constexpr (!kSeparateCost) candidate_equations = problem.linearize(candidate);
      const double candidate_cost = cost_at(candidate, candidate_equations);
      if (candidate_cost <= result.cost) {
        result.x = candidate;
        result.cost = candidate_cost;
        result.equations = std::move(candidate_equations);
        linearized_at_x = !kSeparateCost;
        accepted = true;
        break;
      }
    }
    const bool small = detail::step_is_small<N>(dx, config);
    if (accepted) lambda = std::max(lambda * config.lambda_down, config.min_lambda);
    if (small || (!accepted && !config.adapt)) {
      result.stop = LevenbergMarquardtStop::kConverged;
      result.converged = true;
      break;
    }
    if (!accepted) {
      lambda = lambda > 0.0 ? lambda * config.lambda_up : 1e-6;
    } else if (!linearized_at_x) {
      result.equations = problem.linearize(result.x);
      linearized_at_x = true;
    }
  }
  if (!linearized_at_x) result.equations = problem.linearize(result.x);
  if (result.equations.residuals < config.min_residuals) {
    result.stop = LevenbergMarquardtStop::kTooFewResiduals;
    result.converged = false;
  }
  return result;
}

namespace detail {

// A problem made of a linearize callable alone.
template <typename Linearize>
struct LinearizeOnly {
  Linearize& f;
  template <typename Vector>
  auto linearize(const Vector& x) {
    return f(x);
  }
};

}  // namespace detail

/// The same with a plain callable linearize(x) -> NormalEquations<N> (steps added: x + dx).
template <int N, typename Linearize>
  requires std::is_invocable_v<Linearize&, const typename NormalEquations<N>::Vector&>
LevenbergMarquardtResult<N> levenberg_marquardt(Linearize&& linearize, const typename NormalEquations<N>::Vector& x0,
                                                const LevenbergMarquardtConfig& config = {}) {
  detail::LinearizeOnly<std::remove_reference_t<Linearize>> problem{linearize};
  return levenberg_marquardt<N>(problem, x0, config);
}

}  // namespace slam2d
