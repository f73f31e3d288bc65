// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/normals.hpp"

#include <Eigen/Eigenvalues>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {
namespace {

void validate(const NormalEstimationConfig& config) {
  check_fields(config, "NormalEstimationConfig");
}

// Running sums of the points of one line fit.
struct Scatter {
  Point2 sum = Point2::Zero();
  Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
  int count = 0;
  void add(const Point2& p) {
    sum += p;
    outer += p * p.transpose();
    ++count;
  }
};

// The unit normal of the total least squares line through the scattered points (the eigenvector
// of the smallest eigenvalue of their covariance), facing the origin; zero when too few points.
Point2 fit_normal(const Scatter& scatter, const Point2& point, int min_neighbors) {
  if (scatter.count < min_neighbors) return Point2::Zero();
  const Point2 mean = scatter.sum / scatter.count;
  const Eigen::Matrix2d covariance = scatter.outer / scatter.count - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(covariance);
  Point2 normal = solver.eigenvectors().col(0);
  if (!normal.allFinite() || normal.squaredNorm() < 0.5) return Point2::Zero();
  normal.normalize();
  if (normal.dot(point) > 0.0) normal = -normal;  // face the sensor at the origin
  return normal;
}

}  // namespace

void estimate_normals(PointCloud2& cloud, const KdTree2& tree, const NormalEstimationConfig& config) {
  validate(config);
  check(tree.size() == cloud.size(), "estimate_normals: the kd-tree does not index this cloud");
  const double max_squared = config.max_neighbor_distance * config.max_neighbor_distance;
  std::vector<Neighbor> neighbors;
  cloud.normals.assign(cloud.size(), Point2::Zero());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    tree.nearest_k(cloud.points[i], static_cast<std::size_t>(config.neighbors), neighbors);
    Scatter scatter;
    for (const Neighbor& neighbor : neighbors) {
      if (neighbor.squared_distance <= max_squared) scatter.add(cloud.points[neighbor.index]);
    }
    cloud.normals[i] = fit_normal(scatter, cloud.points[i], config.min_neighbors);
  }
}

void estimate_normals(PointCloud2& cloud, const NormalEstimationConfig& config) {
  validate(config);
  const KdTree2 tree(cloud.points);
  estimate_normals(cloud, tree, config);
}

void estimate_normals_ordered(PointCloud2& cloud, const NormalEstimationConfig& config) {
  validate(config);
  const double max_squared = config.max_neighbor_distance * config.max_neighbor_distance;
  const auto half = static_cast<std::ptrdiff_t>((config.neighbors - 1) / 2 > 0 ? (config.neighbors - 1) / 2 : 1);
  const auto n = static_cast<std::ptrdiff_t>(cloud.size());
  cloud.normals.assign(cloud.size(), Point2::Zero());
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const Point2& point = cloud.points[static_cast<std::size_t>(i)];
    Scatter scatter;
    scatter.add(point);
    // Walk out on each side, stopping at the first neighbour beyond the distance (an edge).
    for (const std::ptrdiff_t direction : {-1, 1}) {
      for (std::ptrdiff_t step = 1; step <= half; ++step) {
        const std::ptrdiff_t j = i + direction * step;
        if (j < 0 || j >= n) break;
        const Point2& neighbor = cloud.points[static_cast<std::size_t>(j)];
        if ((neighbor - point).squaredNorm() > max_squared) break;
        scatter.add(neighbor);
      }
    }
    cloud.normals[static_cast<std::size_t>(i)] = fit_normal(scatter, point, config.min_neighbors);
  }
}

}  // namespace slam2d
