// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/odometry_chain.hpp"

#include <algorithm>

namespace slam2d {

namespace {

bool in_laser_chain(const SensorMessage& message) {
  if (const auto* laser = std::get_if<LaserMessage>(&message)) return laser->has_poses;
  return std::holds_alternative<TruePoseMessage>(message);
}

// The pose between entries a and b at `stamp` (a's pose when their stamps do not span it).
SE2 between_entries(const ChainPose& a, const ChainPose& b, double stamp) {
  const double span = b.stamp - a.stamp;
  if (!(span > 0.0)) return stamp >= b.stamp ? b.pose : a.pose;
  return interpolate(a.pose, b.pose, std::clamp((stamp - a.stamp) / span, 0.0, 1.0));
}

}  // namespace

std::vector<ChainPose> laser_odometry_chain(const std::vector<SensorMessage>& messages) {
  std::vector<ChainPose> chain;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (in_laser_chain(messages[i])) chain.push_back({stamp_of(messages[i]), odometry_pose(messages[i]), i});
  }
  return chain;
}

SE2 chain_pose_at(const std::vector<ChainPose>& chain, std::size_t from, double stamp) {
  std::size_t k = from;
  const std::size_t last = chain.size() - 1;
  if (stamp >= chain[from].stamp) {
    // Forward: the first k with stamp(k + 1) >= stamp.
    while (k < last && chain[k + 1].stamp < stamp && k - from < kMaxChainWalk) ++k;
    return k == last ? chain[last].pose : between_entries(chain[k], chain[k + 1], stamp);
  }
  // Back: the first k with stamp(k - 1) <= stamp.
  while (k > 0 && chain[k - 1].stamp > stamp && from - k < kMaxChainWalk) --k;
  return k == 0 ? chain[0].pose : between_entries(chain[k - 1], chain[k], stamp);
}

std::size_t shift_scan_odometry(std::vector<SensorMessage>& messages, double by) {
  if (by == 0.0) return 0;
  const std::vector<ChainPose> chain = laser_odometry_chain(messages);
  std::vector<SE2> shifted;
  shifted.reserve(chain.size());
  for (std::size_t k = 0; k < chain.size(); ++k) shifted.push_back(chain_pose_at(chain, k, chain[k].stamp + by));
  std::size_t changed = 0;
  for (std::size_t k = 0; k < chain.size(); ++k) {
    if (shifted[k] == chain[k].pose) continue;
    set_odometry_pose(messages[chain[k].message], shifted[k]);
    ++changed;
  }
  return changed;
}

SE2 odometry_pose(const SensorMessage& message) {
  if (const auto* laser = std::get_if<LaserMessage>(&message)) return laser->odom_pose;
  if (const auto* odometry = std::get_if<OdometryMessage>(&message)) return odometry->reading.pose;
  if (const auto* truth = std::get_if<TruePoseMessage>(&message)) return truth->odom_pose;
  return SE2();
}

void set_odometry_pose(SensorMessage& message, const SE2& pose) {
  if (auto* laser = std::get_if<LaserMessage>(&message)) {
    if (laser->type == "ROBOTLASER1") {
      laser->laser_pose = pose * laser->scan.T_robot_sensor;
    } else if (laser->laser_pose == laser->odom_pose) {
      laser->laser_pose = pose;
    }
    laser->odom_pose = pose;
  } else if (auto* odometry = std::get_if<OdometryMessage>(&message)) {
    odometry->reading.pose = pose;
  } else if (auto* truth = std::get_if<TruePoseMessage>(&message)) {
    truth->odom_pose = pose;
  }
}

}  // namespace slam2d
