// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/odometry_chain.hpp"

#include <algorithm>
#include <utility>

namespace slam2d {

bool in_laser_chain(const SensorMessage& message) {
  if (const auto* laser = std::get_if<LaserMessage>(&message)) return laser->has_poses;
  return std::holds_alternative<TruePoseMessage>(message);
}

OdometryChain::OdometryChain(std::vector<ChainSample> samples) : samples_(std::move(samples)) {
  for (std::size_t k = samples_.size(); k-- > 1;) samples_[k - 1].stamp = std::min(samples_[k - 1].stamp, samples_[k].stamp);
}

SE2 OdometryChain::at(std::size_t k, double time) const {
  const auto by_stamp = [](const ChainSample& sample, double t) { return sample.stamp < t; };
  const auto before_stamp = [](double t, const ChainSample& sample) { return t < sample.stamp; };
  const auto begin = samples_.begin();
  const auto from = begin + static_cast<std::ptrdiff_t>(k);
  std::size_t after;  // the first sample at or after `time` (later than it, looking back)
  if (time >= samples_[k].stamp) {
    after = static_cast<std::size_t>(std::lower_bound(from, samples_.end(), time, by_stamp) - begin);
    if (after == k) return samples_[k].pose;
  } else {
    after = static_cast<std::size_t>(std::upper_bound(begin, from, time, before_stamp) - begin);
  }
  if (after == samples_.size()) return samples_.back().pose;
  if (after == 0) return samples_.front().pose;
  // stamp(before) <= time < stamp(after) looking back, stamp(before) < time <= stamp(after) forward.
  const ChainSample& before = samples_[after - 1];
  const ChainSample& next = samples_[after];
  return interpolate(before.pose, next.pose, (time - before.stamp) / (next.stamp - before.stamp));
}

std::optional<ChainSample> chain_sample(std::size_t index, const SensorMessage& message) {
  if (!in_laser_chain(message)) return std::nullopt;
  return ChainSample{index, stamp_of(message), odometry_pose(message)};
}

OdometryChain laser_odometry_chain(const std::vector<SensorMessage>& messages) {
  std::vector<ChainSample> samples;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (const std::optional<ChainSample> sample = chain_sample(i, messages[i])) samples.push_back(*sample);
  }
  return OdometryChain(std::move(samples));
}

std::size_t shift_scan_odometry(std::vector<SensorMessage>& messages, double by) {
  if (by == 0.0) return 0;
  const OdometryChain chain = laser_odometry_chain(messages);
  std::size_t changed = 0;
  for (std::size_t k = 0; k < chain.size(); ++k) {
    const SE2 pose = chain.shifted(k, by);  // from the chain as read: it is not written to
    if (pose == chain[k].pose) continue;
    set_odometry_pose(messages[chain[k].message], pose);
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
