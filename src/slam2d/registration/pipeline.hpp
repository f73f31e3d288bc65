#pragma once
// A modular ICP pipeline in the spirit of libpointmatcher: F. Pomerleau, F. Colas, R. Siegwart,
// S. Magnenat, "Comparing ICP variants on real-world data sets", Autonomous Robots 34(3), 2013
// (Sec. 3, Fig. 1), and "A review of point cloud registration algorithms for mobile robotics",
// Foundations and Trends in Robotics 4(1), 2015 (Sec. 4, the ICP chain). One match runs
//   1. data filters, once: source_filters on the source, target_filters on the target
//      (range clip, voxel grid, random subsample, normals; pipeline_filters.hpp);
//   then, from the guess, until a convergence check holds or max_iterations:
//   2. association: each source point moved by the estimate to its closest target point
//      (kd-tree or projective; pipeline_stages.hpp);
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

#include <vector>

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/match_result.hpp"
#include "slam2d/registration/pipeline_filters.hpp"
#include "slam2d/registration/pipeline_stages.hpp"

namespace slam2d {

struct ConvergenceConfig {
  int max_iterations = 40;     // 1, minimisation steps, >= 1
  double translation = 1e-4;   // m, >= 0; stop when a step moves less than this and turns less than
  double rotation = 1e-4;      // rad, >= 0;  `rotation` (either 0: this check is off)
  double error_change = 0.0;   // 1, >= 0; stop when the mean squared error changes by less than this
                               //    fraction of the previous one (Besl & McKay's tau; 0: off)

  bool operator==(const ConvergenceConfig&) const = default;
};

struct PipelineConfig {
  std::vector<DataFilterConfig> source_filters = {};                    // once per match, in order
  std::vector<DataFilterConfig> target_filters = {NormalsFilter{}};     // once per match, in order
  AssociationConfig association = {};                                   // step 2
  std::vector<OutlierFilterConfig> outlier_filters = {TrimmedFilter{}};  // step 3, in order
  Minimizer minimizer = Minimizer::kPointToLine;                        // step 4
  ConvergenceConfig convergence = {};                                   // step 5
  int min_inliers = 10;      // pairs, >= 3; fewer after the outlier filters: the match fails
  double range_sigma = 0.01;  // m, > 0, range noise for the covariance (Censi 2007)

  bool operator==(const PipelineConfig&) const = default;
};

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
