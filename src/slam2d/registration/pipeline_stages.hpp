// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The matching and error-minimisation stages of the modular ICP pipeline (pipeline.hpp), after
// F. Pomerleau, F. Colas, R. Siegwart, S. Magnenat, "Comparing ICP variants on real-world data
// sets", Autonomous Robots 34(3), 2013, Sec. 3, and their 2015 review, Sec. 4.2 and 4.4:
// - association: the closest target point by kd-tree (associate_closest, nearest_association.hpp,
//   as icp, trimmed_icp and point_to_plane), or by the projective search of ordered scans of
//   A. Censi, "An ICP variant using a point-to-line metric", ICRA 2008, Sec. IV-B: PL-ICP's own
//   exact search with its jump tables and clearance certificates (pl_icp_search.hpp), which
//   finds the same closest point as the kd-tree, faster on scans in beam order;
// - minimisation: point-to-point in closed form (P. Besl, N. McKay, "A method for registration of
//   3-D shapes", PAMI 14(2), 1992, Sec. III-C), or point-to-line / point-to-plane by linear least
//   squares under the small-angle linearisation (K.-L. Low, "Linear least-squares optimization
//   for point-to-plane ICP surface registration", TR04-004, UNC 2004, Sec. 2); both by the
//   shared solvers of closed_form.hpp (the point-to-line one is match_point_to_plane's).
// No stage is implemented twice: see pipeline.hpp for what the pipeline shares with the named
// matchers and why they are not presets of it.

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/pipeline_filters.hpp"

namespace slam2d {

class KdTree2;
namespace pl_icp_detail {
struct TargetIndex;
struct TrackedNearest;
}  // namespace pl_icp_detail

enum class AssociationKind {
  kKdTree,      // the closest target point (any cloud)
  kProjective,  // the same closest point by PL-ICP's projective search (clouds in their sensor
                //   frames, in beam order; any other target falls back to a kd-tree)
};
constexpr auto choices(AssociationKind) {
  return std::array{Choice{"kdtree", AssociationKind::kKdTree}, Choice{"projective", AssociationKind::kProjective}};
}

struct AssociationConfig {
  AssociationKind kind = AssociationKind::kKdTree;
  double max_distance = 1.0;

  bool operator==(const AssociationConfig&) const = default;
};

template <typename Fields>
void describe(Fields& f, AssociationConfig& c) {
  f.choice("kind", c.kind, "the closest target point by kd-tree (any cloud) or by PL-ICP's projective search (clouds in beam order; the same point)");
  f.number("max_distance", c.max_distance, "m", greater_than(0), "no pair is formed with a closest point farther than this");
}

enum class Minimizer {
  kPointToPoint,  // |T p - q|^2, closed form (Besl & McKay 1992)
  kPointToLine,   // (n_q^T (T p - q))^2 on the target normals, linear least squares (Low 2004)
};
constexpr auto choices(Minimizer) {
  return std::array{Choice{"point_to_point", Minimizer::kPointToPoint}, Choice{"point_to_line", Minimizer::kPointToLine}, Choice{"point_to_plane", Minimizer::kPointToLine}};
}

/// The metric a minimiser minimises (for censi_covariance and rms_residual).
ErrorMetric error_metric(Minimizer minimizer);

/// The target's search structure, built once per match over the filtered target, which must
/// outlive it unchanged: a kd-tree, or the target's bearings in ascending order.
class TargetIndex {
 public:
  TargetIndex(const PointCloud2& target, const AssociationConfig& config);
  ~TargetIndex();
  TargetIndex(const TargetIndex&) = delete;
  TargetIndex& operator=(const TargetIndex&) = delete;

  /// Pairs each source point, moved by T_target_source, with its closest target point by the
  /// configured search, when within max_distance; overwrites `pairs` (no allocation once it has
  /// grown). The kd-tree search is associate_closest (nearest_association.hpp), the matchers' own.
  void associate(const std::vector<Point2>& source_points, const SE2& T_target_source,
                 std::vector<PointPair>& pairs) const;

  /// The kd-tree over the target points (nullptr for the projective search).
  const KdTree2* tree() const { return tree_.get(); }

 private:
  AssociationConfig config_;
  std::unique_ptr<KdTree2> tree_;
  std::unique_ptr<pl_icp_detail::TargetIndex> scan_;  // the projective search's index
  // Per source point, the projective search's certificate from the last association: a cache
  // that spares most walks and never changes the answer (the search is exact).
  mutable std::vector<pl_icp_detail::TrackedNearest> tracked_;
};

struct MinimizerStep {
  SE2 step;                   // the update, applied on the left: T <- step * T
  double mean_squared_error;  // m^2, of the pairs at the current T under the metric, before the step
};

/// The paired points handed to the closed-form solvers (closed_form.hpp), gathered by
/// gather_pairs (nearest_association.hpp); reused across iterations, so no allocation once grown.
struct PairedPoints {
  std::vector<Point2> target;
  std::vector<Point2> source;   // moved by the current estimate
  std::vector<Point2> normals;  // the target's (point-to-line)
};

/// One minimisation of the metric over the pairs at the current estimate T_target_source (the
/// source points are moved by it). Point-to-line needs a normal at every pair's target point
/// (the pipeline drops the others first, keep_pairs_with_normals). nullopt when the pairs do not
/// determine the step (fewer than 2 pairs for point-to-point, fewer than 3 or no constraint at
/// all for point-to-line; an unconstrained direction of point-to-line gets no motion).
std::optional<MinimizerStep> minimize_step(Minimizer minimizer, const PointCloud2& target, const PointCloud2& source,
                                           const SE2& T_target_source, const std::vector<PointPair>& pairs,
                                           PairedPoints& paired);

}  // namespace slam2d
