// SPDX-License-Identifier: BSD-3-Clause
// KdTree2 against brute force on random points.

#include "slam2d/registration/kd_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "slam2d/core/rng.hpp"

namespace slam2d {
namespace {

std::vector<Point2> random_points(std::size_t n, Rng& rng) {
  std::vector<Point2> points;
  for (std::size_t i = 0; i < n; ++i) points.emplace_back(rng.uniform(-10.0, 10.0), rng.uniform(-5.0, 5.0));
  return points;
}

std::vector<double> brute_force_squared_distances(const std::vector<Point2>& points, const Point2& query) {
  std::vector<double> d;
  for (const Point2& p : points) d.push_back((p - query).squaredNorm());
  std::sort(d.begin(), d.end());
  return d;
}

TEST(KdTree2, NearestAndKNearestAgreeWithBruteForce) {
  Rng rng(7);
  const std::vector<Point2> points = random_points(500, rng);
  const KdTree2 tree(points);
  ASSERT_EQ(tree.size(), 500U);
  for (int q = 0; q < 100; ++q) {
    const Point2 query(rng.uniform(-12.0, 12.0), rng.uniform(-6.0, 6.0));
    const std::vector<double> truth = brute_force_squared_distances(points, query);
    const Neighbor nearest = tree.nearest(query);
    EXPECT_DOUBLE_EQ(nearest.squared_distance, truth[0]);
    EXPECT_DOUBLE_EQ((points[nearest.index] - query).squaredNorm(), truth[0]);
    const std::vector<Neighbor> k = tree.nearest_k(query, 7);
    ASSERT_EQ(k.size(), 7U);
    for (std::size_t i = 0; i < k.size(); ++i) EXPECT_DOUBLE_EQ(k[i].squared_distance, truth[i]);
  }
}

TEST(KdTree2, WithinRadiusFindsExactlyThePointsInside) {
  Rng rng(11);
  const std::vector<Point2> points = random_points(400, rng);
  const KdTree2 tree(points);
  const Point2 query(1.0, -0.5);
  const double radius = 2.0;
  const std::vector<Neighbor> found = tree.within_radius(query, radius);
  const std::vector<double> truth = brute_force_squared_distances(points, query);
  const auto inside = static_cast<std::size_t>(std::count_if(truth.begin(), truth.end(), [&](double d) { return d <= radius * radius; }));
  ASSERT_EQ(found.size(), inside);
  for (std::size_t i = 1; i < found.size(); ++i) EXPECT_LE(found[i - 1].squared_distance, found[i].squared_distance);
}

TEST(KdTree2, EmptyTreeAndMoreNeighboursThanPoints) {
  const std::vector<Point2> none;
  const KdTree2 empty(none);
  EXPECT_EQ(empty.nearest({0.0, 0.0}).index, 0U);  // == size(): none
  EXPECT_TRUE(empty.nearest_k({0.0, 0.0}, 3).empty());
  EXPECT_TRUE(empty.within_radius({0.0, 0.0}, 1.0).empty());
  const std::vector<Point2> two{{0.0, 0.0}, {1.0, 0.0}};
  const KdTree2 tree(two);
  EXPECT_EQ(tree.nearest_k({0.9, 0.0}, 5).size(), 2U);
  EXPECT_EQ(tree.nearest_k({0.9, 0.0}, 5).front().index, 1U);
}

}  // namespace
}  // namespace slam2d
