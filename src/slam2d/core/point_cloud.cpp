// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/point_cloud.hpp"

namespace slam2d {

PointCloud2 transform(const PointCloud2& cloud_b, const SE2& T_a_b) {
  PointCloud2 cloud_a;
  cloud_a.points.reserve(cloud_b.size());
  for (const Point2& p : cloud_b.points) cloud_a.points.push_back(T_a_b.act(p));
  const Eigen::Matrix2d rotation = T_a_b.rotation();
  cloud_a.normals.reserve(cloud_b.normals.size());
  for (const Point2& n : cloud_b.normals) cloud_a.normals.push_back(rotation * n);
  cloud_a.weights = cloud_b.weights;
  return cloud_a;
}

}  // namespace slam2d
