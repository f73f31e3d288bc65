// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/pipeline.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {
namespace {

bool has_normal_angle_filter(const PipelineConfig& config) {
  for (const OutlierFilterConfig& filter : config.outlier_filters) {
    if (std::holds_alternative<NormalAngleFilter>(filter)) return true;
  }
  return false;
}

// A copy of the cloud without its non-finite points (a NaN would poison every sum), and without
// normals or weights whose count does not match the points.
PointCloud2 finite_copy(const PointCloud2& cloud) {
  PointCloud2 out;
  out.points.reserve(cloud.size());
  const bool normals = cloud.normals.size() == cloud.size();  // malformed extras are dropped
  const bool weights = cloud.weights.size() == cloud.size();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.points[i].allFinite()) continue;
    out.points.push_back(cloud.points[i]);
    if (normals) out.normals.push_back(cloud.normals[i]);
    if (weights) out.weights.push_back(cloud.weights[i]);
  }
  return out;
}

// Normals the configuration needs and the filters did not give: in scan order for the projective
// search (the clouds are scans), else from the k nearest (reusing the target's kd-tree).
void ensure_normals(PointCloud2& cloud, const PipelineConfig& config, const KdTree2* tree) {
  if (cloud.has_normals() || cloud.empty()) return;
  const NormalsFilter defaults;
  const NormalEstimationConfig estimation{.neighbors = defaults.neighbors,
                                          .max_neighbor_distance = defaults.max_neighbor_distance,
                                          .min_neighbors = defaults.min_neighbors};
  if (config.association.kind == AssociationKind::kProjective) {
    estimate_normals_ordered(cloud, estimation);
  } else if (tree != nullptr) {
    estimate_normals(cloud, *tree, estimation);
  } else {
    estimate_normals(cloud, estimation);
  }
}

// Step 1, once per match: the filtered clouds and the target's search structure. Not movable:
// the index points into `target`.
struct Prepared {
  PointCloud2 target;
  PointCloud2 source;
  std::unique_ptr<TargetIndex> index;

  Prepared(const PointCloud2& target_in, const PointCloud2& source_in, const PipelineConfig& config)
      : target(finite_copy(target_in)), source(finite_copy(source_in)) {
    apply_data_filters(target, config.target_filters);
    apply_data_filters(source, config.source_filters);
    index = std::make_unique<TargetIndex>(target, config.association);
    if (config.minimizer == Minimizer::kPointToLine || has_normal_angle_filter(config)) {
      ensure_normals(target, config, index->tree());
    }
    if (has_normal_angle_filter(config)) ensure_normals(source, config, nullptr);
  }
  Prepared(const Prepared&) = delete;
  Prepared& operator=(const Prepared&) = delete;
};

// The buffers of the iterations, sized once per match.
struct Workspace {
  std::vector<PointPair> pairs;
  std::vector<double> scratch;
  PairedPoints paired;

  explicit Workspace(std::size_t source_size) {
    pairs.reserve(source_size);
    scratch.reserve(source_size);
    paired.target.reserve(source_size);
    paired.source.reserve(source_size);
    paired.normals.reserve(source_size);
  }
};

// Steps 2-3: move the source by T, associate, drop pairs point-to-line cannot use, filter.
void match_pairs(const Prepared& prepared, const SE2& T, const PipelineConfig& config, Workspace& work) {
  prepared.index->associate(prepared.source.points, T, work.pairs);
  if (config.minimizer == Minimizer::kPointToLine) keep_pairs_with_normals(prepared.target, work.pairs);
  apply_outlier_filters(config.outlier_filters, {prepared.target, prepared.source, T}, work.pairs, work.scratch);
}

// Step 5: a small step, or a small relative change of the mean squared error.
bool has_converged(const MinimizerStep& step, double previous_error, const ConvergenceConfig& config) {
  const bool small_step = step_below(SE2(), step.step, config.translation, config.rotation);
  const bool small_change = config.error_change > 0.0 && std::isfinite(previous_error) &&
                            std::abs(previous_error - step.mean_squared_error) <= config.error_change * previous_error;
  return small_step || small_change;
}

// A match that could not be made: the guess, flagged, with a huge covariance.
MatchResult failed(const SE2& guess, int iterations, std::size_t pairs) {
  MatchResult result = unmatched(guess, iterations);
  result.inliers = pairs;
  result.residual = std::numeric_limits<double>::quiet_NaN();
  return result;
}

// At the estimate: the final pairs, Censi's covariance of the minimised metric, the RMS
// residual and the degeneracy of the geometry.
MatchResult summarize(Prepared& prepared, const SE2& T, const SE2& guess, bool converged, int iterations,
                      const PipelineConfig& config, Workspace& work) {
  match_pairs(prepared, T, config, work);
  if (work.pairs.size() < static_cast<std::size_t>(config.min_inliers)) {
    return failed(guess, iterations, work.pairs.size());
  }
  MatchResult result;
  result.T_target_source = T;
  result.converged = converged;
  result.iterations = iterations;
  ensure_normals(prepared.target, config, prepared.index->tree());  // for the degeneracy analysis
  finish_match(prepared.target, prepared.source, to_correspondences(work.pairs), error_metric(config.minimizer),
               work.pairs.size(), result, {.range_sigma = config.range_sigma});
  return result;
}

}  // namespace

void validate(const AssociationConfig& association) {
  check_fields(association, "AssociationConfig");
}

void validate(const ConvergenceConfig& convergence) {
  check_fields(convergence, "ConvergenceConfig");
}

void validate(const PipelineConfig& config) {
  check_fields(config, "PipelineConfig");
  for (const DataFilterConfig& filter : config.source_filters) validate(filter);
  for (const DataFilterConfig& filter : config.target_filters) validate(filter);
  for (const OutlierFilterConfig& filter : config.outlier_filters) validate(filter);
}

MatchResult match_pipeline(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                           const PipelineConfig& config) {
  validate(config);
  check(T_target_source_guess.vector().allFinite(), "match_pipeline: the initial guess is not finite");
  Prepared prepared(target, source, config);  // Step 1
  const auto min_inliers = static_cast<std::size_t>(config.min_inliers);
  if (prepared.source.size() < min_inliers || prepared.target.size() < 3) return failed(T_target_source_guess, 0, 0);
  Workspace work(prepared.source.size());
  SE2 T = T_target_source_guess;
  double previous_error = std::numeric_limits<double>::infinity();
  bool converged = false;
  int iterations = 0;
  while (iterations < config.convergence.max_iterations && !converged) {
    match_pairs(prepared, T, config, work);  // Steps 2-3
    if (work.pairs.size() < min_inliers) return failed(T_target_source_guess, iterations, work.pairs.size());
    const auto step = minimize_step(config.minimizer, prepared.target, prepared.source, T, work.pairs, work.paired);  // Step 4
    if (!step) return failed(T_target_source_guess, iterations, work.pairs.size());
    T = step->step * T;
    ++iterations;
    converged = has_converged(*step, previous_error, config.convergence);  // Step 5
    previous_error = step->mean_squared_error;
  }
  return summarize(prepared, T, T_target_source_guess, converged, iterations, config, work);
}

}  // namespace slam2d
