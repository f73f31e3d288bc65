// SPDX-License-Identifier: BSD-3-Clause
// Normal estimation: lines give their perpendicular, facing the sensor; both estimators agree.

#include "slam2d/registration/normals.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

// Two walls seen from the origin, in beam order: x = 4 (y from -3 to 0), then y = 2 (x from 3 to -3).
PointCloud2 two_walls() {
  PointCloud2 cloud;
  for (int i = 0; i <= 30; ++i) cloud.points.emplace_back(4.0, -3.0 + 0.1 * i);    // x = 4
  for (int i = 0; i <= 60; ++i) cloud.points.emplace_back(3.0 - 0.1 * i, 2.0);     // y = 2
  return cloud;
}

void expect_wall_normals(const PointCloud2& cloud) {
  ASSERT_EQ(cloud.normals.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Point2& p = cloud.points[i];
    if (std::abs(p.x() - 4.0) < 1e-9 && p.y() < 0.5) {
      EXPECT_NEAR(cloud.normals[i].x(), -1.0, 1e-9) << i;  // faces the origin
      EXPECT_NEAR(cloud.normals[i].y(), 0.0, 1e-9) << i;
    }
    if (std::abs(p.y() - 2.0) < 1e-9 && p.x() < 2.5) {
      EXPECT_NEAR(cloud.normals[i].x(), 0.0, 1e-9) << i;
      EXPECT_NEAR(cloud.normals[i].y(), -1.0, 1e-9) << i;
    }
  }
}

TEST(Normals, KNearestFitFacesTheSensor) {
  PointCloud2 cloud = two_walls();
  estimate_normals(cloud);
  expect_wall_normals(cloud);
}

TEST(Normals, OrderedFitFacesTheSensor) {
  PointCloud2 cloud = two_walls();
  estimate_normals_ordered(cloud);
  expect_wall_normals(cloud);
}

TEST(Normals, IsolatedPointsGetNoNormal) {
  PointCloud2 cloud;
  cloud.points = {{0.0, 5.0}, {3.0, 5.0}, {6.0, 5.0}};
  estimate_normals(cloud, {.neighbors = 3, .max_neighbor_distance = 0.5, .min_neighbors = 2});
  for (std::size_t i = 0; i < cloud.size(); ++i) EXPECT_FALSE(has_normal(cloud, i));
  estimate_normals_ordered(cloud, {.neighbors = 3, .max_neighbor_distance = 0.5, .min_neighbors = 2});
  for (std::size_t i = 0; i < cloud.size(); ++i) EXPECT_FALSE(has_normal(cloud, i));
}

TEST(Normals, InvalidConfigThrows) {
  PointCloud2 cloud = two_walls();
  EXPECT_THROW(estimate_normals(cloud, {.neighbors = 1}), Error);
  EXPECT_THROW(estimate_normals_ordered(cloud, {.neighbors = 5, .max_neighbor_distance = 0.0}), Error);
}

}  // namespace
}  // namespace slam2d
