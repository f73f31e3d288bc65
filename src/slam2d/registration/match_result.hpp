// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The result every scan matcher returns (the shape of small_gicp's RegistrationResult): the
// estimate, its covariance, how the iteration ended and whether the geometry constrained it.
//
// Every matcher has the signature
//   MatchResult match_<method>(const PointCloud2& target, const PointCloud2& source,
//                              const SE2& T_target_source_guess, const <Method>Config& = {});
// T_target_source maps source points into the target frame: p_target = T_target_source * p_source.

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <limits>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct MatchResult {
  SE2 T_target_source;                                   // the estimate
  Covariance3 covariance = unknown_covariance();  // m^2, m rad, rad^2; kUnknownVariance when unknown
  bool converged = false;       // the stopping test was met before the iteration limit
  int iterations = 0;           // of the matcher's main loop (poses scored, for search methods)
  std::size_t inliers = 0;      // correspondences kept at the estimate
  double residual = 0.0;        // m, RMS of the inlier residuals at the estimate (search methods: see their header)
  bool degenerate = false;      // the scene does not constrain every direction (degeneracy.hpp)
  Eigen::Vector3d weak_direction = Eigen::Vector3d::Zero();  // (x, y, theta), unit; the least constrained direction
  // The eigenvalues behind `degenerate` (degeneracy.hpp), ascending, of the information with rotation
  // scaled to arc length (1/m^2): their ratio smallest / largest is the degeneracy measure. NaN when
  // the matcher made no such analysis.
  Eigen::Vector3d information_eigenvalues = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  // Map matchers (scan to map; 0 from the scan-to-scan matchers):
  double inlier_fraction = 0.0; // 1, in [0, 1]: inliers / the points offered (the matcher's own inlier test)
  bool seen_from_behind = false;  // most inliers see the map's surfaces from their far side (where both
                                  // clouds carry normals: correlative_map_match.hpp)
  double score = 0.0;           // 1, in [0, 1]: a search method's response at its best pose (correlative: the
                                // share of the points on the table's occupied cells); 0 from least squares
  double cost = 0.0;            // the objective minimised, at the estimate, in the matcher's units (Hector:
                                // sum r^2 / 2 with the prior's cost): compares starts of one matcher on one scan

  /// The inverse covariance; zero when the covariance is unknown (kUnknownVariance all along the
  /// diagonal, unknown_covariance()): unknown is zero information, never a confident guess. A
  /// single direction at kUnknownVariance gets 1 / kUnknownVariance, next to nothing.
  Eigen::Matrix3d information() const {
    if (covariance.diagonal().minCoeff() >= kUnknownVariance) return Eigen::Matrix3d::Zero();
    return information_from_covariance(covariance);
  }
};

/// Any matcher with its configuration bound: what scan odometry, benchmarks and SLAM front ends
/// take (matcher_registry.hpp makes one from a name or a YAML preset).
using Matcher = std::function<MatchResult(const PointCloud2& target, const PointCloud2& source,
                                          const SE2& T_target_source_guess)>;

}  // namespace slam2d
