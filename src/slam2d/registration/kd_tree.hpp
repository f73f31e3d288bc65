// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Nearest neighbours in the plane: a kd-tree over a caller's points (nanoflann, J. L. Blanco and
// P. K. Rai, 2014). This header is the only place nanoflann is seen. The tree indexes the vector
// in place: the points must outlive the tree and must not change while it is used.

#include <cstddef>
#include <memory>
#include <vector>

#include "slam2d/core/point_cloud.hpp"

namespace slam2d {

struct Neighbor {
  std::size_t index = 0;
  double squared_distance = 0.0;  // m^2
};

class KdTree2 {
 public:
  explicit KdTree2(const std::vector<Point2>& points, int leaf_size = 10);
  ~KdTree2();
  KdTree2(const KdTree2&) = delete;
  KdTree2& operator=(const KdTree2&) = delete;
  KdTree2(KdTree2&&) noexcept;
  KdTree2& operator=(KdTree2&&) noexcept;

  std::size_t size() const;
  const std::vector<Point2>& points() const;

  /// The closest point, or none (index = size()) when the tree is empty.
  Neighbor nearest(const Point2& query) const;
  /// Up to k closest points, nearest first.
  std::vector<Neighbor> nearest_k(const Point2& query, std::size_t k) const;
  /// As nearest_k, into a caller's buffer (no allocation once it has grown); returns the count.
  std::size_t nearest_k(const Point2& query, std::size_t k, std::vector<Neighbor>& out) const;
  /// All points within `radius` (m), nearest first.
  std::vector<Neighbor> within_radius(const Point2& query, double radius) const;

 private:
  struct Index;
  std::unique_ptr<Index> index_;
};

}  // namespace slam2d
