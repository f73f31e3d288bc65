// SPDX-License-Identifier: BSD-3-Clause
// The likelihood-field table of LocalizationMap (tiled, with a border) against the field itself.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "slam2d/core/rng.hpp"
#include "slam2d/localization/localization_map.hpp"

namespace slam2d {
namespace {

// A 6 m x 4 m map at 0.1 m, rotated, with a few obstacle cells.
OccupancyMap small_map() {
  OccupancyMap map;
  map.resolution = 0.1;
  map.origin = SE2(-2.0, 1.0, 0.3);
  map.width = 60;
  map.height = 40;
  map.cells.assign(60 * 40, OccupancyMap::kFree);
  for (int i = 0; i < 60; ++i) map.at(i, 20) = OccupancyMap::kOccupied;
  map.at(5, 5) = map.at(50, 35) = OccupancyMap::kOccupied;
  return map;
}

TEST(LikelihoodFieldModel, TableLookupsMatchTheFieldAtTheNearestSample) {
  const LocalizationMap map(small_map());
  const LikelihoodField& field = map.field();
  // Points all over the field and beyond it on every side, one at a time, at a pose that puts
  // them into field cells: the table holds round(1000 log beam_likelihood) of the sample.
  Rng rng(11);
  const SE2 T_map_robot(0.4, -0.2, 1.1);
  int outside = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d p_robot(rng.uniform(-12.0, 12.0), rng.uniform(-12.0, 12.0));
    const Eigen::Vector2d in_field = field.origin().inverse().act(T_map_robot.act(p_robot)) / field.resolution();
    const int x = static_cast<int>(std::floor(in_field.x()));
    const int y = static_cast<int>(std::floor(in_field.y()));
    double expected;
    if (x >= 0 && y >= 0 && x < field.width() && y < field.height()) {
      expected = std::round(1000.0 * std::log(field.beam_likelihood(field.cell_center(x, y)))) / 1000.0;
    } else {
      ++outside;  // max_distance from every obstacle: the field's own value far away
      expected = std::round(1000.0 * std::log(field.beam_likelihood(T_map_robot.act(p_robot)))) / 1000.0;
    }
    ASSERT_NEAR(map.scan_log_likelihood({p_robot}, T_map_robot), expected, 1.5e-3) << p_robot.transpose();
  }
  EXPECT_GT(outside, 200);
  // A scan sums its points (more than one chunk of 64).
  std::vector<Eigen::Vector2d> points;
  double sum = 0.0;
  for (int i = 0; i < 150; ++i) {
    points.emplace_back(rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0));
    sum += map.scan_log_likelihood({points.back()}, T_map_robot);
  }
  EXPECT_NEAR(map.scan_log_likelihood(points, T_map_robot), sum, 1e-9);
  EXPECT_EQ(map.scan_log_likelihood({}, T_map_robot), 0.0);
}

}  // namespace
}  // namespace slam2d
