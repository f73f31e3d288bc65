// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Surface normals of a 2D point cloud, for point-to-line and point-to-plane metrics and for the
// Fisher information (degeneracy.hpp). A normal is the unit eigenvector of the smallest
// eigenvalue of the neighbours' scatter matrix (total least squares line fit), turned to face
// the sensor at the cloud's origin. Where a point has too few neighbours its normal is the zero
// vector: callers treat a zero normal as "no normal" and skip the point.

#include <cstddef>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"

namespace slam2d {

class KdTree2;

struct NormalEstimationConfig {
  int neighbors = 5;
  double max_neighbor_distance = 0.5;
  int min_neighbors = 3;
};

template <typename Fields>
void describe(Fields& f, NormalEstimationConfig& c) {
  f.number("neighbors", c.neighbors, "1", at_least(2), "k nearest points in a fit (the point itself included)");
  f.number("max_neighbor_distance", c.max_neighbor_distance, "m", greater_than(0), "farther neighbours are left out of the fit");
  f.number("min_neighbors", c.min_neighbors, "1", at_least(2), "points in the fit (itself included) below which the normal is zero");
}

/// Normals from the k nearest neighbours (any cloud, ordered or not); sets cloud.normals.
void estimate_normals(PointCloud2& cloud, const NormalEstimationConfig& config = {});
/// The same with a kd-tree already built over cloud.points.
void estimate_normals(PointCloud2& cloud, const KdTree2& tree, const NormalEstimationConfig& config = {});

/// Normals of an ordered scan (points in beam order) from the points within
/// (neighbors - 1) / 2 places on either side in the scan, no kd-tree; sets cloud.normals.
void estimate_normals_ordered(PointCloud2& cloud, const NormalEstimationConfig& config = {});

/// True when the cloud has a normal for point i (a non-zero one).
inline bool has_normal(const PointCloud2& cloud, std::size_t i) {
  return i < cloud.normals.size() && cloud.normals[i].squaredNorm() > 0.5;
}

}  // namespace slam2d
