#pragma once
// A small Levenberg-Marquardt loop over normal_equations.hpp (K. Levenberg 1944, D. W. Marquardt
// 1963; the lambda schedule of Numerical Recipes, 3rd ed., Sec. 15.5.2): linearise, solve the
// damped step, keep it when the cost drops (and relax lambda), else raise lambda and retry.
// With initial_lambda = 0 and adapt = false every step is a plain Gauss-Newton step.
//
// The parameters live in R^N and steps are added (x + dx); callers with a manifold (an SE2
// pose) pass a `plus` that retracts the step.

#include <cmath>
#include <optional>
#include <utility>

#include "slam2d/optim/normal_equations.hpp"

namespace slam2d {

struct LevenbergMarquardtConfig {
  int max_iterations = 20;       // accepted plus rejected steps, >= 1
  double initial_lambda = 1e-4;  // 1, damping of the first step (0: Gauss-Newton)
  double lambda_up = 10.0;       // 1, factor on a rejected step
  double lambda_down = 0.1;      // 1, factor on an accepted step
  bool adapt = true;             // false: every step is accepted (pure Gauss-Newton when lambda = 0)
  double min_step_norm = 1e-10;  // |dx| below this counts as converged
  Damping damping = Damping::kDiagonal;
};

template <int N>
struct LevenbergMarquardtResult {
  typename NormalEquations<N>::Vector x;
  NormalEquations<N> equations;  // linearised at x (H gives the covariance)
  int iterations = 0;
  bool converged = false;        // the last step was shorter than min_step_norm
  double cost = 0.0;             // at x
};

/// Minimises the cost that linearize(x) -> NormalEquations<N> accumulates, from x0.
/// plus(x, dx) applies a step (default: x + dx).
template <int N, typename Linearize, typename Plus>
LevenbergMarquardtResult<N> levenberg_marquardt(Linearize&& linearize, const typename NormalEquations<N>::Vector& x0,
                                                const LevenbergMarquardtConfig& config, Plus&& plus) {
  LevenbergMarquardtResult<N> result;
  result.x = x0;
  result.equations = linearize(result.x);
  result.cost = result.equations.cost;
  double lambda = config.initial_lambda;
  for (int iteration = 0; iteration < config.max_iterations; ++iteration) {
    result.iterations = iteration + 1;
    const auto dx = solve_step(result.equations, {.lambda = lambda, .damping = config.damping});
    if (!dx) {
      if (!config.adapt || lambda == 0.0) break;  // singular and undamped: nothing more to do
      lambda *= config.lambda_up;
      continue;
    }
    const typename NormalEquations<N>::Vector candidate = plus(result.x, *dx);
    const NormalEquations<N> candidate_equations = linearize(candidate);
    if (!config.adapt || candidate_equations.cost <= result.cost) {
      result.x = candidate;
      result.equations = candidate_equations;
      result.cost = candidate_equations.cost;
      lambda *= config.lambda_down;
      if (dx->norm() < config.min_step_norm) {
        result.converged = true;
        break;
      }
    } else {
      lambda = lambda > 0.0 ? lambda * config.lambda_up : 1e-6;
    }
  }
  return result;
}

template <int N, typename Linearize>
LevenbergMarquardtResult<N> levenberg_marquardt(Linearize&& linearize, const typename NormalEquations<N>::Vector& x0,
                                                const LevenbergMarquardtConfig& config = {}) {
  return levenberg_marquardt<N>(std::forward<Linearize>(linearize), x0, config,
                                [](const auto& x, const auto& dx) -> typename NormalEquations<N>::Vector { return x + dx; });
}

}  // namespace slam2d
