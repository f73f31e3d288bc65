// SPDX-License-Identifier: BSD-3-Clause
// Trimmed ICP: D. Chetverikov, D. Svirko, D. Stepanov, P. Krsek, "The Trimmed Iterative Closest
// Point algorithm", ICPR 2002 (Sec. 3, steps 1-5, and the overlap objective psi). See
// trimmed_icp.hpp.

#include "slam2d/registration/trimmed_icp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"

namespace slam2d {
namespace {

constexpr std::size_t kMinPoints = 3;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// psi(n / N) = (S_n / n) / (n / N)^(1 + lambda) = S_n N^(1 + lambda) / n^(2 + lambda): the
// factors n^-(2 + lambda), n = 1..N, computed once per match (the constant N^(1 + lambda) does
// not move the minimum).
std::vector<double> psi_factors(std::size_t count, double lambda) {
  std::vector<double> factors(count);
  for (std::size_t n = 1; n <= count; ++n) factors[n - 1] = std::pow(static_cast<double>(n), -(2.0 + lambda));
  return factors;
}

// The n in [ceil(min_overlap N), N] minimising S_n * factors[n - 1] (ties to the larger n).
std::size_t minimise_psi(const std::vector<double>& sorted, double min_overlap, const std::vector<double>& factors) {
  const std::size_t count = sorted.size();
  const auto first = static_cast<std::size_t>(std::ceil(min_overlap * static_cast<double>(count) - 1e-9));
  double sum = 0.0;
  double best_psi = kInfinity;
  std::size_t best = count;
  for (std::size_t n = 1; n <= count; ++n) {
    sum += sorted[n - 1];  // S_n, the trimmed sum of squares
    if (n < first) continue;
    const double psi = sum * factors[n - 1];
    if (psi <= best_psi) {
      best_psi = psi;
      best = n;
    }
  }
  return best;
}

// The xi re-estimations of kAtConvergence before the current xi is accepted regardless.
constexpr int kMaxOverlapUpdates = 8;

struct TrimmedBuffers {
  std::vector<PointPair> pairs;
  std::vector<double> sorted_distances;
  std::vector<double> scratch;  // keep_closest_pairs
  std::vector<double> psi_factors;
  std::vector<Point2> target_points;
  std::vector<Point2> source_points;
};

// The squared distances of all current pairs, before trimming (sorted when psi needs them).
void collect_distances(TrimmedBuffers& buffers) {
  buffers.sorted_distances.clear();
  for (const PointPair& pair : buffers.pairs) buffers.sorted_distances.push_back(pair.squared_distance);
}

// N_po minimising psi over the collected squared distances, sorted once.
std::size_t estimate_pair_count(TrimmedBuffers& buffers, const TrimmedIcpConfig& config) {
  std::sort(buffers.sorted_distances.begin(), buffers.sorted_distances.end());
  return minimise_psi(buffers.sorted_distances, config.min_overlap, buffers.psi_factors);
}

// N_po for this iteration: xi N_p for a given overlap, psi's minimiser per iteration, or the
// count kept from the last estimate (`current`, 0 = all pairs, xi = 1); at least
// min_correspondences when there are as many pairs.
std::size_t pair_count(TrimmedBuffers& buffers, const TrimmedIcpConfig& config, std::size_t current) {
  const std::size_t count = buffers.pairs.size();
  std::size_t kept = current == 0 ? count : current;
  if (config.overlap > 0.0) {
    kept = static_cast<std::size_t>(std::llround(config.overlap * static_cast<double>(count)));
  } else if (config.overlap_estimation == OverlapEstimation::kPerIteration) {
    kept = estimate_pair_count(buffers, config);
  }
  return std::clamp(kept, std::min(count, static_cast<std::size_t>(config.min_correspondences)), count);
}

// Step 2: the `kept` pairs with the smallest squared distances (keep_closest_pairs); returns the
// trimmed MSE e = S'_LTS / N_po.
double keep_best_pairs(std::vector<PointPair>& pairs, std::size_t kept, std::vector<double>& scratch) {
  if (kept == 0) return kInfinity;
  keep_closest_pairs(pairs, kept, scratch);
  double sum = 0.0;
  for (const PointPair& pair : pairs) sum += pair.squared_distance;
  return sum / static_cast<double>(kept);
}

// Step 3's convergence test: a small trimmed MSE, or a small relative change of it.
bool trimmed_mse_settled(double mse, double previous_mse, const TrimmedIcpConfig& config) {
  return mse <= config.min_trimmed_mse || std::abs(previous_mse - mse) <= config.min_relative_change * mse;
}

}  // namespace

void validate(const TrimmedIcpConfig& config) {
  check_fields(config, "TrimmedIcpConfig");
}

std::size_t trimmed_pair_count(const std::vector<double>& sorted_squared_distances, double min_overlap,
                               double lambda) {
  if (sorted_squared_distances.empty()) return 0;
  return minimise_psi(sorted_squared_distances, min_overlap, psi_factors(sorted_squared_distances.size(), lambda));
}

MatchResult match_trimmed_icp(const PointCloud2& target, const PointCloud2& source,
                              const SE2& T_target_source_guess, const TrimmedIcpConfig& config) {
  validate(config);
  if (target.size() < kMinPoints || source.size() < kMinPoints) return unmatched(T_target_source_guess);
  const KdTree2 tree(target.points);
  const auto min_pairs = static_cast<std::size_t>(config.min_correspondences);
  const bool estimate_at_convergence =
      config.overlap == 0.0 && config.overlap_estimation == OverlapEstimation::kAtConvergence;
  TrimmedBuffers buffers;
  if (config.overlap == 0.0) buffers.psi_factors = psi_factors(source.size(), config.lambda);
  MatchResult result;
  SE2 T = T_target_source_guess;
  double previous_mse = kInfinity;
  std::size_t overlap_count = 0;  // kAtConvergence: N_po of the current xi (0: xi = 1)
  int overlap_updates = 0;
  while (true) {
    associate_closest(tree, source.points, T, kInfinity, buffers.pairs);  // Step 1: closest points, d_i^2
    if (config.overlap == 0.0) collect_distances(buffers);
    const std::size_t kept = pair_count(buffers, config, overlap_count);
    const double mse = keep_best_pairs(buffers.pairs, kept, buffers.scratch);  // Step 2: N_po least d_i^2, e
    if (kept < min_pairs) break;
    if (trimmed_mse_settled(mse, previous_mse, config)) {  // Step 3
      if (!estimate_at_convergence || overlap_updates == kMaxOverlapUpdates) {
        result.converged = true;
        break;
      }
      // Converged for this xi: minimise psi here; the same xi ends it, another goes on from here.
      const std::size_t estimate = std::max(estimate_pair_count(buffers, config), std::min(kept, min_pairs));
      if (estimate == kept) {
        result.converged = true;
        break;
      }
      overlap_count = estimate;
      ++overlap_updates;
      previous_mse = kInfinity;
      continue;
    }
    if (result.iterations == config.max_iterations) break;
    // Step 4: the motion minimising S'_LTS over the kept pairs (step 5, moving the points, is
    // the next association at T).
    gather_pairs(buffers.pairs, target, source, SE2(), buffers.target_points, buffers.source_points);
    T = solve_point_to_point(config.solver, buffers.target_points, buffers.source_points);
    ++result.iterations;
    previous_mse = mse;
  }
  result.T_target_source = T;  // the kept pairs are those at T
  finish_match(with_normals(target, tree), source, to_correspondences(buffers.pairs), ErrorMetric::kPointToPoint,
               min_pairs, result);
  return result;
}

}  // namespace slam2d
