// ReverseOdometryRepair on hand-made odometry (FR079 integrates reversing as forward driving), and
// the likelihood-field table of LocalizationMap (tiled, with a border) against the field itself.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "slam2d/core/rng.hpp"
#include "slam2d/localization/localization_map.hpp"
#include "slam2d/localization/odometry_repair.hpp"

namespace slam2d {
namespace {

OdometryReading with_tv(double tv) {
  OdometryReading reading;
  reading.tv = tv;
  return reading;
}

TEST(ReverseOdometryRepair, MirrorsForwardStepsWhileTvIsNegative) {
  ReverseOdometryRepair repair;
  const double half_pi = std::numbers::pi / 2;
  // The first scan: its raw pose is kept.
  EXPECT_TRUE(repair.repair(SE2(1.0, 2.0, half_pi)).is_approx(SE2(1.0, 2.0, half_pi)));
  // Facing +y, the raw pose advances 0.5 m along +y and turns 0.1 rad while tv < 0: the robot
  // backed up 0.5 m (to y = 1.5), the turn is kept.
  repair.observe(with_tv(-0.4));
  repair.observe(with_tv(-0.5));
  EXPECT_TRUE(repair.repair(SE2(1.0, 2.5, half_pi + 0.1)).is_approx(SE2(1.0, 1.5, half_pi + 0.1), 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 1u);
  // Forward driving with tv > 0: the step (0.2 m along the new heading) is applied as it is, from
  // the repaired pose.
  repair.observe(with_tv(0.3));
  const SE2 raw_next = SE2(1.0, 2.5, half_pi + 0.1) * SE2(0.2, 0.0, 0.0);
  const SE2 expected = SE2(1.0, 1.5, half_pi + 0.1) * SE2(0.2, 0.0, 0.0);
  EXPECT_TRUE(repair.repair(raw_next).is_approx(expected, 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 1u);
}

TEST(ReverseOdometryRepair, KeepsConsistentStepsAndStepsWithoutVelocity) {
  ReverseOdometryRepair repair;
  repair.repair(SE2(0.0, 0.0, 0.0));
  // Already backwards while tv < 0: kept.
  repair.observe(with_tv(-0.5));
  EXPECT_TRUE(repair.repair(SE2(-0.3, 0.0, 0.0)).is_approx(SE2(-0.3, 0.0, 0.0), 1e-12));
  // No ODOM message since the last scan: kept, whatever the last tv was.
  EXPECT_TRUE(repair.repair(SE2(0.2, 0.0, 0.0)).is_approx(SE2(0.2, 0.0, 0.0), 1e-12));
  // Turning on the spot with tv < 0: no translation to mirror.
  repair.observe(with_tv(-0.01));
  EXPECT_TRUE(repair.repair(SE2(0.2, 0.0, 0.5)).is_approx(SE2(0.2, 0.0, 0.5), 1e-12));
  EXPECT_EQ(repair.reversed_steps(), 0u);
}

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
