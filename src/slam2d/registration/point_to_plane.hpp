// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Point-to-plane ICP by linear least squares: K.-L. Low, "Linear least-squares optimization for
// point-to-plane ICP surface registration", TR04-004, UNC Chapel Hill, 2004, in the plane (the
// "plane" is the line through a target point along its normal). Each iteration pairs every
// source point, moved by the current estimate, with its closest target point (kd-tree), rejects
// far pairs and targets without a normal, and solves Low's small-angle linear system for the
// increment (solve_point_to_plane, closed_form.hpp), applied with the exact rotation. Target
// normals are the target's own, or estimate_normals (k nearest neighbours) when it has none.
// It stops when an increment is below the step tolerances or the estimate comes back to one of
// its last four (a cycle of the pairs, which no further iteration leaves: PoseCycle in
// nearest_association.hpp, as CSM's loop detection); both count as converged.
//
// Preset: configs/point-to-plane.yaml. Method page: docs/methods/icp.md.

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

class KdTree2;

struct PointToPlaneConfig {
  int max_iterations = 30;
  double max_correspondence_distance = 0.3;
  int min_correspondences = 10;
  double min_translation_step = 1e-4;
  double min_rotation_step = 1e-4;
  int normal_neighbors = 5;
  double normal_max_distance = 0.5;
  int normal_min_neighbors = 3;
};

template <typename Fields>
void describe(Fields& f, PointToPlaneConfig& c) {
  f.number("max_iterations", c.max_iterations, "1", at_least(1), "linear solves before giving up");
  f.number("max_correspondence_distance", c.max_correspondence_distance, "m", greater_than(0),
           "pairs farther apart are rejected (at 1 m, surfaces one scan does not see pull the tests' pairs 2.4 cm off)");
  f.number("min_correspondences", c.min_correspondences, "1", at_least(3), "fewer pairs and the match fails");
  f.number("min_translation_step", c.min_translation_step, "m", at_least(0), "stop when an increment moves less than this ...");
  f.number("min_rotation_step", c.min_rotation_step, "rad", at_least(0), "... and turns less than this");
  f.number("normal_neighbors", c.normal_neighbors, "1", at_least(2), "k of the kNN normal fit when the target has no normals");
  f.number("normal_max_distance", c.normal_max_distance, "m", greater_than(0), "neighbours farther away stay out of the fit");
  f.number("normal_min_neighbors", c.normal_min_neighbors, "1", at_least(2), "fewer fitted points and the target point has no normal");
}

/// Throws Error when a field is out of its range.
void validate(const PointToPlaneConfig& config);

/// Registers `source` to `target` (both in their sensor frames) from the guess. The covariance
/// is Censi's closed form for the point-to-line metric (the pairs as Correspondence with
/// target2 = kNoPoint, along the target normals); residual is the RMS point-to-line distance.
MatchResult match_point_to_plane(const PointCloud2& target, const PointCloud2& source,
                                 const SE2& T_target_source_guess, const PointToPlaneConfig& config = {});
/// The same with a kd-tree already built over target.points (a map matched by many scans).
MatchResult match_point_to_plane(const KdTree2& tree, const PointCloud2& target, const PointCloud2& source,
                                 const SE2& T_target_source_guess, const PointToPlaneConfig& config = {});

}  // namespace slam2d
