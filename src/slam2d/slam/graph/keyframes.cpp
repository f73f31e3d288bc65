#include "slam2d/slam/graph/keyframes.hpp"

#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

void validate(const KeyframeConfig& config) {
  check(std::isfinite(config.min_distance) && config.min_distance >= 0.0, "keyframes: min_distance must be >= 0");
  check(std::isfinite(config.min_angle) && config.min_angle >= 0.0, "keyframes: min_angle must be >= 0");
  check(std::isfinite(config.min_time) && config.min_time >= 0.0, "keyframes: min_time must be >= 0");
}

KeyframeSelector::KeyframeSelector(const KeyframeConfig& config) : config_(config) { validate(config_); }

bool KeyframeSelector::is_keyframe(const SE2& T_map_robot, double stamp) const {
  if (!last_pose_) return true;
  const SE2 motion = last_pose_->between(T_map_robot);
  if (motion.translation().norm() >= config_.min_distance) return true;
  if (std::abs(motion.theta()) >= config_.min_angle) return true;
  return config_.min_time > 0.0 && std::abs(stamp - last_stamp_) >= config_.min_time;
}

void KeyframeSelector::accept(const SE2& T_map_robot, double stamp) {
  last_pose_ = T_map_robot;
  last_stamp_ = stamp;
}

}  // namespace slam2d
