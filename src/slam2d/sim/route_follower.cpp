// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/route_follower.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr double kProgressWindow = 1.0;  // m, how far ahead the robot's place on the route is searched
constexpr double kCornerExit = 0.3;      // m, a corner keeps limiting the speed this far past it

double wrap_distance(double d, double length) {
  d = std::fmod(d, length);
  if (d < -0.5 * length) d += length;
  if (d >= 0.5 * length) d -= length;
  return d;
}

}  // namespace

RouteFollower::RouteFollower(std::vector<Eigen::Vector2d> route, const RouteFollowerConfig& config)
    : config_(config) {
  for (const Eigen::Vector2d& p : route) {
    check(p.allFinite(), "route: waypoints must be finite");
    if (points_.empty() || (p - points_.back()).norm() > 1e-9) points_.push_back(p);
  }
  if (points_.size() > 1 && (points_.back() - points_.front()).norm() <= 1e-9) points_.pop_back();
  check(points_.size() >= 2, "route: needs at least two distinct waypoints");
  const std::size_t n = points_.size();
  points_.push_back(points_.front());  // closing point
  arc_.assign(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) arc_[i + 1] = arc_[i] + (points_[i + 1] - points_[i]).norm();
  length_ = arc_.back();
  // A corner of turn angle phi taken on an arc of radius r passes r (1 / cos(phi / 2) - 1)
  // inside the corner; the radius that keeps this at corner_cut sets the speed v = omega_max r.
  corner_speed_.assign(n, config_.speed);
  for (std::size_t j = 0; j < n; ++j) {
    const Eigen::Vector2d in = points_[j] - points_[(j + n - 1) % n];
    const Eigen::Vector2d out = points_[j + 1] - points_[j];
    const double phi = std::abs(angle_difference(std::atan2(out.y(), out.x()), std::atan2(in.y(), in.x())));
    const double cut_per_radius = 1.0 / std::max(std::cos(0.5 * phi), 1e-9) - 1.0;
    const double radius = cut_per_radius > 0.0 ? config_.corner_cut / cut_per_radius : std::numeric_limits<double>::infinity();
    corner_speed_[j] = std::clamp(config_.max_turn_rate * radius, config_.min_speed, config_.speed);
  }
}

SE2 RouteFollower::start_pose() const {
  const Eigen::Vector2d d = points_[1] - points_[0];
  return SE2(points_[0], std::atan2(d.y(), d.x()));
}

Eigen::Vector2d RouteFollower::point_at(double s) const {
  s = std::fmod(s, length_);
  if (s < 0.0) s += length_;
  const auto it = std::upper_bound(arc_.begin(), arc_.end(), s);
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(it - arc_.begin()), arc_.size() - 1) - 1;
  const double segment = arc_[i + 1] - arc_[i];
  const double f = segment > 0.0 ? (s - arc_[i]) / segment : 0.0;
  return points_[i] + f * (points_[i + 1] - points_[i]);
}

// The robot's place on the route: the nearest route point within a short window ahead of the
// last one, so that where the route crosses or repeats itself the robot keeps its own place.
void RouteFollower::advance_progress(const Eigen::Vector2d& position) {
  const std::size_t n = points_.size() - 1;
  const double lap_start = std::floor(progress_ / length_) * length_;
  std::size_t i = static_cast<std::size_t>(std::upper_bound(arc_.begin(), arc_.end(), progress_ - lap_start) - arc_.begin());
  i = std::min(std::max<std::size_t>(i, 1), n) - 1;
  double segment_start = lap_start + arc_[i];
  double best_distance = std::numeric_limits<double>::infinity();
  double best_progress = progress_;
  for (std::size_t count = 0; count <= n && segment_start <= progress_ + kProgressWindow; ++count) {
    const double segment = arc_[i + 1] - arc_[i];
    const double lo = std::max(0.0, progress_ - segment_start);
    const double hi = std::min(segment, progress_ + kProgressWindow - segment_start);
    if (segment > 0.0 && lo <= hi) {
      const Eigen::Vector2d direction = (points_[i + 1] - points_[i]) / segment;
      const double along = std::clamp((position - points_[i]).dot(direction), lo, hi);
      const double distance = (points_[i] + along * direction - position).norm();
      if (distance < best_distance) {
        best_distance = distance;
        best_progress = segment_start + along;
      }
    }
    segment_start += segment;
    i = (i + 1) % n;
  }
  progress_ = std::max(progress_, best_progress);
}

double RouteFollower::corner_speed_limit() const {
  double limit = config_.speed;
  const double lookahead = config_.min_lookahead;
  for (std::size_t j = 0; j < corner_speed_.size(); ++j) {
    const double ahead = wrap_distance(arc_[j] - progress_, length_);
    if (ahead < -kCornerExit) continue;
    // Pure pursuit starts turning about one look-ahead before the corner: be slow by then.
    const double braking = std::max(0.0, ahead - lookahead - config_.lookahead_time * corner_speed_[j]);
    limit = std::min(limit, std::sqrt(corner_speed_[j] * corner_speed_[j] + 2.0 * config_.max_acceleration * braking));
  }
  return limit;
}

VelocityCommand RouteFollower::update(const SE2& T_world_robot, const VelocityCommand& current, double dt) {
  advance_progress(T_world_robot.translation());
  // Pure pursuit: the arc through the look-ahead point has curvature 2 sin(alpha) / distance.
  const double lookahead = config_.min_lookahead + config_.lookahead_time * current.v;
  const Eigen::Vector2d target = T_world_robot.inverse().act(point_at(progress_ + lookahead));
  const double alpha = std::atan2(target.y(), target.x());
  const double curvature = 2.0 * std::sin(alpha) / std::max(target.norm(), 1e-6);
  // Speed: cruise, brake for corners, slow when facing away, and never faster than the turn-rate
  // limit allows on the current arc.
  double v_wanted = std::min(corner_speed_limit(), config_.speed * std::max(0.1, std::cos(alpha)));
  if (curvature != 0.0) v_wanted = std::min(v_wanted, config_.max_turn_rate / std::abs(curvature));
  VelocityCommand next;
  const double dv = config_.max_acceleration * dt;
  next.v = std::max(0.0, current.v + std::clamp(v_wanted - current.v, -dv, dv));
  const double omega_wanted = std::clamp(next.v * curvature, -config_.max_turn_rate, config_.max_turn_rate);
  const double domega = config_.max_angular_acceleration * dt;
  next.omega = std::clamp(current.omega + std::clamp(omega_wanted - current.omega, -domega, domega),
                          -config_.max_turn_rate, config_.max_turn_rate);
  return next;
}

}  // namespace slam2d
