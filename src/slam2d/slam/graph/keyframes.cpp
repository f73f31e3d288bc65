// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/graph/keyframes.hpp"

#include <cmath>
#include <cstdint>
#include <unordered_set>

#include "slam2d/core/error.hpp"

namespace slam2d {

void validate(const KeyframeConfig& config) {
  check_fields(config, "KeyframeConfig");
  check(config.redundant_radius == 0.0 || config.redundant_angle > 0.0,
        "KeyframeConfig: redundant_angle must be > 0 when redundant_radius is");
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

PointCloud2 map_cloud(const std::vector<const Keyframe*>& keyframes, const std::vector<SE2>& T_map_keyframe,
                      const Eigen::Vector2d& center, double radius, double voxel) {
  PointCloud2 map;
  const double radius_squared = radius * radius;
  std::unordered_set<std::uint64_t> occupied;
  const auto first_in_voxel = [&](const Eigen::Vector2d& point) {
    if (voxel <= 0.0) return true;
    const auto x = static_cast<std::int64_t>(std::floor(point.x() / voxel));
    const auto y = static_cast<std::int64_t>(std::floor(point.y() / voxel));
    return occupied.insert((static_cast<std::uint64_t>(x) << 32) ^ static_cast<std::uint32_t>(y)).second;
  };
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    const PointCloud2& cloud = keyframes[k]->cloud;
    const SE2& T = T_map_keyframe[k];
    const Eigen::Matrix2d R = T.rotation();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Eigen::Vector2d point = T * cloud.points[i];
      if ((point - center).squaredNorm() > radius_squared || !first_in_voxel(point)) continue;
      map.points.push_back(point);
      map.normals.push_back(R * cloud.normals[i]);
    }
  }
  return map;
}

}  // namespace slam2d
