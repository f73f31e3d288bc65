// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/trajectory.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

std::vector<SE2> poses_of(const Trajectory& trajectory) {
  std::vector<SE2> poses;
  poses.reserve(trajectory.size());
  for (const StampedPose& stamped : trajectory) poses.push_back(stamped.pose);
  return poses;
}

Trajectory with_poses(const Trajectory& trajectory, const std::vector<SE2>& poses) {
  check(poses.size() == trajectory.size(), "with_poses: one pose per stamp");
  Trajectory out;
  out.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) out.push_back(trajectory[i].stamp, poses[i]);
  return out;
}

bool Trajectory::is_monotonic() const { return backwards_steps() == 0; }

std::size_t Trajectory::backwards_steps() const {
  std::size_t count = 0;
  for (std::size_t i = 1; i < poses_.size(); ++i) {
    if (poses_[i].stamp < poses_[i - 1].stamp) ++count;
  }
  return count;
}

Trajectory Trajectory::sorted_by_stamp() const {
  std::vector<StampedPose> sorted = poses_;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  return Trajectory(std::move(sorted));
}

double Trajectory::path_length() const {
  double length = 0.0;
  for (std::size_t i = 1; i < poses_.size(); ++i) {
    length += (poses_[i].pose.translation() - poses_[i - 1].pose.translation()).norm();
  }
  return length;
}

std::optional<SE2> Trajectory::interpolate(double stamp) const {
  check(is_monotonic(), "Trajectory::interpolate: stamps go backwards; sort the trajectory first");
  if (poses_.empty() || stamp < poses_.front().stamp || stamp > poses_.back().stamp) return std::nullopt;
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), stamp,
                                      [](const StampedPose& p, double t) { return p.stamp < t; });
  if (after->stamp == stamp || after == poses_.begin()) return after->pose;
  const auto before = std::prev(after);
  const double s = (stamp - before->stamp) / (after->stamp - before->stamp);
  return slam2d::interpolate(before->pose, after->pose, s);
}

StampIndex::StampIndex(const Trajectory& trajectory) {
  sorted_.reserve(trajectory.size());
  for (std::size_t i = 0; i < trajectory.size(); ++i) sorted_.emplace_back(trajectory[i].stamp, i);
  std::stable_sort(sorted_.begin(), sorted_.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
}

std::optional<std::size_t> StampIndex::nearest(double stamp, double tolerance) const {
  if (sorted_.empty()) return std::nullopt;
  const auto after = std::lower_bound(sorted_.begin(), sorted_.end(), stamp,
                                      [](const auto& entry, double t) { return entry.first < t; });
  auto best = sorted_.end();
  if (after != sorted_.end()) best = after;
  if (after != sorted_.begin()) {
    const auto before = std::prev(after);
    if (best == sorted_.end() || stamp - before->first <= best->first - stamp) best = before;
  }
  if (std::abs(best->first - stamp) > tolerance) return std::nullopt;
  return best->second;
}

}  // namespace slam2d
