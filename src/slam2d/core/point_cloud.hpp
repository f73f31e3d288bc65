// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PointCloud2: 2D points with optional per-point normals and weights.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "slam2d/core/se2.hpp"

namespace slam2d {

using Point2 = Eigen::Vector2d;

struct PointCloud2 {
  std::vector<Point2> points;   // m
  std::vector<Point2> normals;  // unit vectors; empty, or one per point
  std::vector<double> weights;  // empty, or one per point

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_weights() const { return !weights.empty(); }
};

/// The cloud moved by T_a_b: points (and normals) from frame b into frame a.
PointCloud2 transform(const PointCloud2& cloud_b, const SE2& T_a_b);

}  // namespace slam2d
