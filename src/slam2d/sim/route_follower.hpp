// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A smooth path-following controller for a differential-drive robot on a closed polyline route:
// pure pursuit (Coulter, "Implementation of the Pure Pursuit Path Tracking Algorithm",
// CMU-RI-TR-92-01, 1992) for the turn rate, with a speed profile that brakes for corners so that
// each corner can be taken within the turn-rate limit, and acceleration limits on both velocities.

#include <vector>

#include <Eigen/Core>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct RouteFollowerConfig {
  double speed = 0.6;
  double max_turn_rate = 1.0;
  double max_acceleration = 0.5;
  double max_angular_acceleration = 4.0;
  double min_lookahead = 0.3;
  double lookahead_time = 0.5;
  double corner_cut = 0.1;
  double min_speed = 0.05;
};

template <typename Fields>
void describe(Fields& f, RouteFollowerConfig& c) {
  f.number("speed", c.speed, "m/s", greater_than(0), "cruise speed");
  f.number("max_turn_rate", c.max_turn_rate, "rad/s", greater_than(0), "fastest turn");
  f.number("max_acceleration", c.max_acceleration, "m/s^2", greater_than(0), "largest change of speed");
  f.number("max_angular_acceleration", c.max_angular_acceleration, "rad/s^2", greater_than(0),
           "largest change of turn rate");
  f.number("min_lookahead", c.min_lookahead, "m", at_least(0), "pure-pursuit look-ahead at standstill");
  f.number("lookahead_time", c.lookahead_time, "s", at_least(0), "look-ahead grows by speed * this");
  f.number("corner_cut", c.corner_cut, "m", at_least(0), "how far a corner's arc may pass inside the corner");
  f.number("min_speed", c.min_speed, "m/s", greater_than(0), "the slowest corner speed");
}

/// A velocity command: forward speed (m/s) and turn rate (rad/s, counter-clockwise).
struct VelocityCommand {
  double v = 0.0;
  double omega = 0.0;
};

class RouteFollower {
 public:
  /// `route`: closed polyline (the last point connects back to the first), >= 2 distinct points.
  /// Throws Error for fewer points or non-finite coordinates.
  RouteFollower(std::vector<Eigen::Vector2d> route, const RouteFollowerConfig& config);

  /// route[0], facing route[1].
  SE2 start_pose() const;
  /// The next command for a robot at `T_world_robot` driving `current`, to hold for `dt` s.
  VelocityCommand update(const SE2& T_world_robot, const VelocityCommand& current, double dt);
  /// Distance driven along the route so far (m), counting repeats: laps = progress / length.
  double progress() const { return progress_; }
  double route_length() const { return length_; }

 private:
  Eigen::Vector2d point_at(double s) const;
  void advance_progress(const Eigen::Vector2d& position);
  /// The speed (m/s) allowed now so that every corner within braking distance can be taken.
  double corner_speed_limit() const;

  RouteFollowerConfig config_;
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> arc_;           // m, arc length at each point; arc_.back() = length_ (closing point)
  std::vector<double> corner_speed_;  // m/s, the speed allowed at each point's corner
  double length_ = 0.0;
  double progress_ = 0.0;
};

}  // namespace slam2d
