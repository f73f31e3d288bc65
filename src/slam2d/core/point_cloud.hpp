// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PointCloud2: 2D points with optional per-point normals and weights.

#include <Eigen/Core>
#include <cmath>
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

/// Whether a step from a surface's point goes on along the surface's line (unit direction
/// `along`): its offset across the line is within 5 cm and 2 % of its length (range noise and a
/// wall's roughness at the step's scale). A grazing wall sampled a metre apart goes on along its
/// line; a depth edge, or a mixed pixel between two surfaces, does not.
inline bool continues_line(const Point2& along, const Point2& step) {
  return std::abs(along.x() * step.y() - along.y() * step.x()) <= 0.05 + 0.02 * step.norm();
}

}  // namespace slam2d
