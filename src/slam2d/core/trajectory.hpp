// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Trajectory: stamped poses, kept in the order they were added (real logs may go back in time).

#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/se2.hpp"

namespace slam2d {

struct StampedPose {
  double stamp = 0.0;  // s
  SE2 pose;
};

class Trajectory {
 public:
  Trajectory() = default;
  explicit Trajectory(std::vector<StampedPose> poses) : poses_(std::move(poses)) {}

  void push_back(double stamp, const SE2& pose) { poses_.push_back({stamp, pose}); }
  void reserve(std::size_t n) { poses_.reserve(n); }
  std::size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  const StampedPose& operator[](std::size_t i) const { return poses_[i]; }
  const StampedPose& front() const { return poses_.front(); }
  const StampedPose& back() const { return poses_.back(); }
  auto begin() const { return poses_.begin(); }
  auto end() const { return poses_.end(); }
  const std::vector<StampedPose>& poses() const { return poses_; }

  /// True when stamps never decrease.
  bool is_monotonic() const;
  /// Number of places where a stamp is smaller than the one before it.
  std::size_t backwards_steps() const;
  /// A copy ordered by stamp (stable: equal stamps keep their order).
  Trajectory sorted_by_stamp() const;
  /// Sum of translation distances between consecutive poses (m).
  double path_length() const;

  /// The pose at `stamp`, interpolated between the two poses around it; nullopt outside the
  /// covered time span. Throws Error if the stamps are not monotonic (sort first).
  std::optional<SE2> interpolate(double stamp) const;

 private:
  std::vector<StampedPose> poses_;
};

/// The poses alone, in order.
std::vector<SE2> poses_of(const Trajectory& trajectory);
/// The trajectory's stamps with other poses, one per stamp (Error otherwise).
Trajectory with_poses(const Trajectory& trajectory, const std::vector<SE2>& poses);

/// Finds the pose nearest in time to a stamp, whatever the order of the trajectory.
class StampIndex {
 public:
  explicit StampIndex(const Trajectory& trajectory);
  /// Index (into the trajectory) of the pose whose stamp is nearest to `stamp`, if within `tolerance` s.
  std::optional<std::size_t> nearest(double stamp, double tolerance) const;

 private:
  std::vector<std::pair<double, std::size_t>> sorted_;  // (stamp, index)
};

}  // namespace slam2d
