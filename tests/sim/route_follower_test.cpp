// SPDX-License-Identifier: BSD-3-Clause
// The route follower on a plain square: it drives laps, keeps its limits and stays on the route.

#include <gtest/gtest.h>

#include <cmath>

#include "slam2d/core/error.hpp"
#include "slam2d/sim/route_follower.hpp"
#include "slam2d/sim/world.hpp"

namespace slam2d {
namespace {

using Eigen::Vector2d;

struct Drive {
  std::vector<SE2> poses;
  std::vector<VelocityCommand> commands;
  double laps = 0.0;
};

Drive drive(const std::vector<Vector2d>& route, const RouteFollowerConfig& config, double duration, double dt) {
  RouteFollower follower(route, config);
  Drive result;
  SE2 pose = follower.start_pose();
  VelocityCommand command;
  for (int k = 0; k * dt < duration; ++k) {
    command = follower.update(pose, command, dt);
    pose = pose * SE2::exp(Eigen::Vector3d(command.v * dt, 0.0, command.omega * dt));
    result.poses.push_back(pose);
    result.commands.push_back(command);
  }
  result.laps = follower.progress() / follower.route_length();
  return result;
}

const std::vector<Vector2d> kSquare = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};

TEST(RouteFollower, StartsAtTheFirstWaypointFacingTheSecond) {
  const RouteFollower follower(kSquare, {});
  EXPECT_TRUE(follower.start_pose().is_approx(SE2(0, 0, 0)));
  EXPECT_NEAR(follower.route_length(), 16.0, 1e-12);
  const RouteFollower closed({{0, 0}, {0, 2}, {1, 2}, {0, 0}}, {});  // a repeated first point is dropped
  EXPECT_NEAR(closed.start_pose().theta(), std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(closed.route_length(), 3.0 + std::sqrt(5.0), 1e-12);
}

TEST(RouteFollower, DrivesLapsWithinItsLimits) {
  const RouteFollowerConfig config{.speed = 0.6, .max_turn_rate = 1.0, .max_acceleration = 0.5};
  const double dt = 0.01;
  const Drive d = drive(kSquare, config, 120.0, dt);
  // 16 m laps at <= 0.6 m/s with four corners each: between 3 and 4.5 laps in 120 s.
  EXPECT_GT(d.laps, 3.0);
  EXPECT_LT(d.laps, 4.5);
  double max_offset = 0.0;
  for (std::size_t k = 0; k < d.poses.size(); ++k) {
    const VelocityCommand& c = d.commands[k];
    ASSERT_GE(c.v, 0.0);
    ASSERT_LE(c.v, config.speed + 1e-12);
    ASSERT_LE(std::abs(c.omega), config.max_turn_rate + 1e-12);
    if (k > 0) {
      ASSERT_LE(std::abs(c.v - d.commands[k - 1].v), config.max_acceleration * dt + 1e-12);
      ASSERT_LE(std::abs(c.omega - d.commands[k - 1].omega), config.max_angular_acceleration * dt + 1e-12);
    }
    // Distance to the square's outline.
    const Vector2d p = d.poses[k].translation();
    double offset = 1e9;
    for (std::size_t i = 0; i < kSquare.size(); ++i) {
      offset = std::min(offset, distance_to_segment(p, kSquare[i], kSquare[(i + 1) % kSquare.size()]));
    }
    max_offset = std::max(max_offset, offset);
  }
  // Corners are cut by about corner_cut (0.1 m); the tracking error adds a little.
  EXPECT_LT(max_offset, 0.15);
  EXPECT_GT(max_offset, 0.03);
}

TEST(RouteFollower, SlowsDownForCorners) {
  const Drive d = drive(kSquare, {}, 60.0, 0.01);
  // Near the corner (4, 0) on the first lap the robot is slow, mid-edge it cruises.
  double corner_speed = 1e9, edge_speed = 0.0;
  for (std::size_t k = 0; k < d.poses.size() && d.poses[k].y() < 2.0; ++k) {
    const Vector2d p = d.poses[k].translation();
    if ((p - Vector2d(4, 0)).norm() < 0.3) corner_speed = std::min(corner_speed, d.commands[k].v);
    if (std::abs(p.x() - 2.0) < 0.05 && p.y() < 0.5) edge_speed = std::max(edge_speed, d.commands[k].v);
  }
  EXPECT_NEAR(edge_speed, 0.6, 1e-9);
  // A 90 deg corner cut by 0.1 m is an arc of radius 0.1 / (sqrt(2) - 1) = 0.24 m: 0.24 m/s at 1 rad/s.
  EXPECT_LT(corner_speed, 0.3);
  EXPECT_GT(corner_speed, 0.1);
}

TEST(RouteFollower, RejectsDegenerateRoutes) {
  EXPECT_THROW(RouteFollower({}, {}), Error);
  EXPECT_THROW(RouteFollower({{1, 1}, {1, 1}}, {}), Error);
  EXPECT_THROW(RouteFollower({{0, 0}, {std::nan(""), 1}}, {}), Error);
}

}  // namespace
}  // namespace slam2d
