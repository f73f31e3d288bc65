// SPDX-License-Identifier: BSD-3-Clause
// Boolean and soft-weighted ICP in the six-step framework of Rusinkiewicz & Levoy 2001 (see the
// header for the steps and equations).
#include "slam2d/registration/weighted_icp.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/closed_form.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {
namespace {

constexpr std::size_t kMinCloudPoints = 3;

/// One source-target pair of an iteration.
struct Pair {
  std::size_t source = 0;
  std::size_t target = 0;
  double distance = 0.0;  // m, |T p - q| at the estimate the pair was found at
  double weight = 1.0;
};

/// What every step reads: the clouds (with the normals the config needs), the target's tree and
/// the selected source points.
struct Problem {
  const PointCloud2& target;
  const PointCloud2& source;
  const KdTree2& tree;
  std::vector<std::size_t> selected;
};

NormalEstimationConfig normal_config(const WeightedIcpConfig& config) {
  return {.neighbors = config.normal_neighbors, .max_neighbor_distance = config.normal_max_distance, .min_neighbors = 3};
}

/// `cloud` itself when it has normals, else a copy in `storage` with normals from its k nearest
/// neighbours (`tree` over its points when given).
const PointCloud2& with_normals(const PointCloud2& cloud, PointCloud2& storage, const WeightedIcpConfig& config,
                                const KdTree2* tree = nullptr) {
  check(cloud.normals.empty() || cloud.normals.size() == cloud.size(),
        "weighted ICP: a cloud has normals, but not one per point");
  if (cloud.has_normals()) return cloud;
  storage = cloud;
  if (tree) {
    estimate_normals(storage, *tree, normal_config(config));
  } else {
    estimate_normals(storage, normal_config(config));
  }
  return storage;
}

// Step 1: select.
std::vector<std::size_t> select_points(const PointCloud2& source, int every) {
  std::vector<std::size_t> selected;
  selected.reserve(source.size() / static_cast<std::size_t>(every) + 1);
  for (std::size_t i = 0; i < source.size(); i += static_cast<std::size_t>(every)) selected.push_back(i);
  return selected;
}

// Step 2: match each selected point, moved by T, to its closest target point.
void match_closest_points(const Problem& problem, const SE2& T_target_source, std::vector<Pair>& pairs) {
  pairs.clear();
  for (const std::size_t i : problem.selected) {
    const Neighbor nearest = problem.tree.nearest(T_target_source * problem.source.points[i]);
    if (nearest.index >= problem.tree.size()) continue;
    pairs.push_back({i, nearest.index, std::sqrt(nearest.squared_distance), 1.0});
  }
}

// Step 3: weight, Eq. (1)-(2).
void weight_pairs(std::vector<Pair>& pairs, const WeightedIcpConfig& config) {
  for (Pair& pair : pairs) pair.weight = pair_weight(pair.distance, config);
}

bool normals_compatible(const Problem& problem, const Pair& pair, const SE2& T_target_source, double min_cosine) {
  if (!has_normal(problem.target, pair.target) || !has_normal(problem.source, pair.source)) return true;
  const Point2 source_normal = T_target_source.rotation() * problem.source.normals[pair.source];
  return source_normal.dot(problem.target.normals[pair.target]) >= min_cosine;
}

// Step 4: reject far pairs, statistical outliers (mean + k sigma), incompatible normals and the
// pairs the weighting switched off.
void reject_pairs(const Problem& problem, const SE2& T_target_source, const WeightedIcpConfig& config,
                  std::vector<Pair>& pairs) {
  std::erase_if(pairs, [&](const Pair& p) { return p.weight <= 0.0 || p.distance > config.max_correspondence_distance; });
  if (config.reject_sigma_factor > 0.0 && pairs.size() > 1) {
    double sum = 0.0, sum_squares = 0.0;
    for (const Pair& p : pairs) {
      sum += p.distance;
      sum_squares += p.distance * p.distance;
    }
    const double n = static_cast<double>(pairs.size());
    const double mean = sum / n;
    const double sigma = std::sqrt(std::max(0.0, sum_squares / n - mean * mean));
    const double limit = mean + config.reject_sigma_factor * sigma;
    std::erase_if(pairs, [&](const Pair& p) { return p.distance > limit; });
  }
  if (config.max_normal_angle > 0.0) {
    const double min_cosine = std::cos(config.max_normal_angle);
    std::erase_if(pairs, [&](const Pair& p) { return !normals_compatible(problem, p, T_target_source, min_cosine); });
  }
}

/// Steps 2-4 at the estimate T.
void associate(const Problem& problem, const SE2& T_target_source, const WeightedIcpConfig& config,
               std::vector<Pair>& pairs) {
  match_closest_points(problem, T_target_source, pairs);
  weight_pairs(pairs, config);
  reject_pairs(problem, T_target_source, config, pairs);
}

/// The pairs as the point lists of the shared closed-form solvers (closed_form.hpp).
struct PairLists {
  std::vector<Point2> target_points, target_normals, source_points;
  std::vector<double> weights;

  void clear() {
    target_points.clear();
    target_normals.clear();
    source_points.clear();
    weights.clear();
  }
};

// Steps 5-6, point-to-point: the closed-form minimum of Eq. (3) (Arun / Umeyama SVD, weighted).
std::optional<SE2> minimise_point_to_point(const Problem& problem, const std::vector<Pair>& pairs, PairLists& lists) {
  lists.clear();
  for (const Pair& p : pairs) {
    lists.target_points.push_back(problem.target.points[p.target]);
    lists.source_points.push_back(problem.source.points[p.source]);
    lists.weights.push_back(p.weight);
  }
  if (lists.weights.empty()) return std::nullopt;
  return solve_point_to_point_svd(lists.target_points, lists.source_points, &lists.weights);
}

// Steps 5-6, point-to-line: Eq. (4) linearised at the estimate T (Low 2004's small-angle linear
// least squares on the source points moved by T), composed on the left of T.
std::optional<SE2> minimise_point_to_line(const Problem& problem, const std::vector<Pair>& pairs, const SE2& T,
                                          PairLists& lists) {
  lists.clear();
  for (const Pair& p : pairs) {
    if (!has_normal(problem.target, p.target)) continue;
    lists.target_points.push_back(problem.target.points[p.target]);
    lists.target_normals.push_back(problem.target.normals[p.target]);
    lists.source_points.push_back(T * problem.source.points[p.source]);
    lists.weights.push_back(p.weight);
  }
  if (lists.weights.size() < kMinCloudPoints) return std::nullopt;
  const std::optional<SE2> step =
      solve_point_to_plane(lists.target_points, lists.target_normals, lists.source_points, &lists.weights);
  if (!step) return std::nullopt;
  return *step * T;
}

std::optional<SE2> minimise(const Problem& problem, const std::vector<Pair>& pairs, const SE2& T,
                            const WeightedIcpConfig& config, PairLists& lists) {
  return config.metric == ErrorMetric::kPointToPoint ? minimise_point_to_point(problem, pairs, lists)
                                                     : minimise_point_to_line(problem, pairs, T, lists);
}

bool small_update(const SE2& before, const SE2& after, const WeightedIcpConfig& config) {
  return (after.translation() - before.translation()).norm() <= config.translation_tolerance &&
         std::abs(angle_difference(after.theta(), before.theta())) <= config.rotation_tolerance;
}

/// Re-associates at the estimate and fills covariance, residual, inliers and degeneracy.
MatchResult finish(const Problem& problem, const SE2& T, const WeightedIcpConfig& config, MatchResult result) {
  std::vector<Pair> pairs;
  associate(problem, T, config, pairs);
  std::vector<Correspondence> correspondences;
  correspondences.reserve(pairs.size());
  for (const Pair& p : pairs) correspondences.push_back({p.source, p.target, kNoPoint, p.weight});
  result.T_target_source = T;
  result.inliers = correspondences.size();
  if (correspondences.size() < kMinCloudPoints) {
    result.converged = false;
    result.degenerate = true;
    return result;
  }
  result.covariance =
      censi_covariance(problem.target, problem.source, T, correspondences, config.metric, {config.range_sigma});
  result.residual = rms_residual(problem.target, problem.source, T, correspondences, config.metric);
  apply(analyze_degeneracy(problem.target, problem.source, T, correspondences), result);
  return result;
}

bool usable_count(const std::vector<Pair>& pairs, const WeightedIcpConfig& config) {
  return pairs.size() >= static_cast<std::size_t>(config.min_correspondences);
}

}  // namespace

void validate(const WeightedIcpConfig& c) {
  check_fields(c, "WeightedIcpConfig");
}

double pair_weight(double distance, const WeightedIcpConfig& config) {
  const double s = distance / config.weight_distance;
  if (config.weighting == IcpWeighting::kBoolean) return s <= 1.0 ? 1.0 : 0.0;  // Eq. (1)
  switch (config.soft_kernel) {                                                 // Eq. (2)
    case SoftWeightKernel::kLinear: return std::max(0.0, 1.0 - s);
    case SoftWeightKernel::kGaussian: return std::exp(-0.5 * s * s);
    case SoftWeightKernel::kCauchy: return 1.0 / (1.0 + s * s);
  }
  return 0.0;
}

MatchResult match_weighted_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                               const WeightedIcpConfig& config) {
  validate(config);
  if (target.size() < kMinCloudPoints || source.size() < kMinCloudPoints) return unmatched(T_target_source_guess, 0);
  const KdTree2 tree(target.points);  // indexes target.points, which the copy with normals shares
  PointCloud2 target_storage, source_storage;
  const PointCloud2& target_n = with_normals(target, target_storage, config, &tree);  // degeneracy needs them
  const PointCloud2& source_n = config.max_normal_angle > 0.0 ? with_normals(source, source_storage, config) : source;
  const Problem problem{target_n, source_n, tree, select_points(source_n, config.select_every)};

  MatchResult result;
  SE2 T = T_target_source_guess;
  std::vector<Pair> pairs;
  PairLists lists;
  for (int iteration = 1; iteration <= config.max_iterations; ++iteration) {
    result.iterations = iteration;
    associate(problem, T, config, pairs);                                         // steps 2-4
    if (!usable_count(pairs, config)) return unmatched(T_target_source_guess, iteration);
    const std::optional<SE2> next = minimise(problem, pairs, T, config, lists);       // steps 5-6
    if (!next) return unmatched(T_target_source_guess, iteration);
    const bool converged = small_update(T, *next, config);
    T = *next;
    if (converged) {
      result.converged = true;
      break;
    }
  }
  return finish(problem, T, config, result);
}

MatchResult match_boolean_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                              const WeightedIcpConfig& config) {
  WeightedIcpConfig boolean = config;
  boolean.weighting = IcpWeighting::kBoolean;
  return match_weighted_icp(target, source, T_target_source_guess, boolean);
}

MatchResult match_soft_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                           const WeightedIcpConfig& config) {
  WeightedIcpConfig soft = config;
  soft.weighting = IcpWeighting::kSoft;
  return match_weighted_icp(target, source, T_target_source_guess, soft);
}

}  // namespace slam2d
