// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A modular ICP pipeline in the spirit of libpointmatcher: F. Pomerleau, F. Colas, R. Siegwart,
// S. Magnenat, "Comparing ICP variants on real-world data sets", Autonomous Robots 34(3), 2013
// (Sec. 3, Fig. 1), and "A review of point cloud registration algorithms for mobile robotics",
// Foundations and Trends in Robotics 4(1), 2015 (Sec. 4, the ICP chain). One match runs
//   1. data filters, once: source_filters on the source, target_filters on the target
//      (range clip, voxel grid, random subsample, normals; pipeline_filters.hpp);
//   then, from the guess, until a convergence check holds or max_iterations:
//   2. association: each source point moved by the estimate to its closest target point
//      (kd-tree or PL-ICP's exact projective search; pipeline_stages.hpp);
//   3. outlier filters, in order (max distance, trimmed, median factor, normal angle);
//   4. error minimisation: point-to-point (closed form) or point-to-line (linear least squares),
//      the step applied on the left, T <- step T;
//   5. convergence checks: a small step (translation and rotation), a small relative change of
//      the mean squared error;
// and at the estimate: the final pairs, Censi's covariance of the minimised metric, the RMS
// residual and the degeneracy analysis.
//
// A preset from code, with designated initialisers:
//   const PipelineConfig besl{.target_filters = {}, .association = {.max_distance = 2.0},
//                             .outlier_filters = {}, .minimizer = Minimizer::kPointToPoint};
// or from YAML (pipeline_config.hpp, configs/pipeline*.yaml). No virtual calls: each stage is a
// std::visit per filter and iteration, the per-point loops are plain functions.
//
// One ICP framework (issue 21): the pipeline is built from the named matchers' stages, not the
// other way round. Its kd association, normal filter, trimming, pair gathering, step test and
// result are those of icp / trimmed_icp / point_to_plane (nearest_association.hpp: one PointPair,
// associate_closest, keep_pairs_with_normals, keep_closest_pairs, gather_pairs, step_below,
// finish_match); its projective association is PL-ICP's search (pl_icp_search.hpp); its
// minimisers are the closed-form solvers of closed_form.hpp (point-to-point SVD, Low's
// point-to-line step, match_point_to_plane's); normals and covariance come from normals.hpp and
// covariance.hpp. The named matchers are not presets of the pipeline, because none is exactly a
// pipeline configuration: icp registers the original points and stops on an absolute change of
// the error after the step (the pipeline: a step on the moved points, a relative change before
// it) and has Besl's acceleration; point_to_plane keeps its estimate when pairs run short (the
// pipeline returns the guess) and matches against a caller's kd-tree (graph SLAM's map, bit for
// bit); trimmed_icp estimates the overlap, PL-ICP has Censi's exact step and rejections, and
// IDC, GA-ICP and correlative are other algorithms. Presets would have changed their results.

#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/match_result.hpp"
#include "slam2d/registration/pipeline_filters.hpp"
#include "slam2d/registration/pipeline_stages.hpp"

namespace slam2d {

struct ConvergenceConfig {
  int max_iterations = 40;
  double translation = 1e-4;
  double rotation = 1e-4;
  double error_change = 0.0;

  bool operator==(const ConvergenceConfig&) const = default;
};

template <typename Fields>
void describe(Fields& f, ConvergenceConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "minimisation steps");
  f.number("translation", c.translation, "m", at_least(0), "stop when a step moves less than this and turns less than `rotation` (either 0: off)");
  f.number("rotation", c.rotation, "rad", at_least(0), "");
  f.number("error_change", c.error_change, "1", at_least(0),
           "stop when the mean squared error changes by less than this fraction of the previous one (Besl & McKay's tau; 0: off)");
}

struct PipelineConfig {
  std::vector<DataFilterConfig> source_filters = {};
  std::vector<DataFilterConfig> target_filters = {NormalsFilter{}};
  AssociationConfig association = {};
  std::vector<OutlierFilterConfig> outlier_filters = {TrimmedFilter{}};
  Minimizer minimizer = Minimizer::kPointToLine;
  ConvergenceConfig convergence = {};
  int min_inliers = 10;
  double range_sigma = 0.01;

  bool operator==(const PipelineConfig&) const = default;
};

template <typename Fields>
void describe(Fields& f, PipelineConfig& c) {
  f.list("source_filters", c.source_filters, "1. data filters on the source, once per match, in order");
  f.list("target_filters", c.target_filters, "1. data filters on the target, once per match, in order");
  f.section("association", c.association, "2. association");
  f.list("outlier_filters", c.outlier_filters, "3. outlier filters, every iteration, in order");
  f.choice("minimizer", c.minimizer, "4. error minimisation (point_to_plane: point_to_line)");
  f.section("convergence", c.convergence, "5. convergence checks");
  f.number("min_inliers", c.min_inliers, "pairs", at_least(3), "fewer after the outlier filters: the match fails");
  f.number("range_sigma", c.range_sigma, "m", greater_than(0), "range noise for the covariance (Censi 2007)");
}

/// Throw Error naming the stage and the parameter when a value is out of range.
void validate(const AssociationConfig& association);
void validate(const ConvergenceConfig& convergence);
void validate(const PipelineConfig& config);  // every stage

/// Registers `source` to `target` (clouds in their sensor frames; for the projective search in
/// beam order) from T_target_source_guess. Normals the configuration needs and the filters did
/// not provide are estimated with the defaults of NormalsFilter (in scan order for the
/// projective search): target normals for point-to-line, both for the normal-angle filter, and
/// the target's for the degeneracy analysis. Too few points or pairs (min_inliers), or a
/// singular step: converged = false, the guess, a huge covariance and degenerate = true.
MatchResult match_pipeline(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                           const PipelineConfig& config = {});

}  // namespace slam2d
