// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Repair of odometry that integrates reverse driving as forward driving.
//
// In the FR079 raw log (fr079.clf.gz) the ODOM velocity tv is negative while the robot backs up
// (e.g. 197.9-200.4 s after the first scan: tv = -0.5 m/s), yet the odometry pose x, y advances
// along the heading: the pose integrates |tv|. The relations of Kuemmerle et al. 2009 and the
// SLAM-corrected log agree that the robot moved backwards there: 294 of the 4934 scan-to-scan
// odometry steps of that log move forward while tv < 0, and 317 are repaired with those that back
// up and drive on within one step. Intel and ACES have none. Every method that takes the
// odometry as its motion guess is sent the wrong way by such a step; scan matching catches it
// while the scans are dense, and fails when they are not (FR079 with every second scan dropped:
// graph SLAM 0.66 m instead of 0.034 m).
//
// ReverseOdometryRepair rebuilds the odometry from the scan-to-scan increments. The pose travelled
// sum |tv| dt along an increment (dx, dy, dtheta) that moves forward (dx > 0); the robot travelled
// sum tv dt. So the increment's translation is scaled by the signed share
//     s = sum tv / sum |tv|   (over the ODOM messages since the pose last moved)
// to (s dx, s dy, dtheta): s = -1 mirrors a step driven wholly in reverse, and a step that backs up
// and drives on (an odometry freeze over a change of direction, then its catch-up) keeps its net
// travel. The sums run from the last increment that moved, so a frozen pose does not lose them.
// It trusts tv's sign over the poses only where the log has shown that sign to mean what it says:
// - it repairs only after the log has driven forward with mean tv > min_speed for
//   `min_forward_steps` increments, and while the steps it reverses stay at most half as many (a
//   log whose tv is negative when the robot drives forward is left alone);
// - once the log has backed up `reverse_steps_to_trust_poses` increments with mean tv < -min_speed
//   *and* the pose moving backwards, the poses record reversing themselves, and the repair switches
//   itself off for good.
// Increments without ODOM messages, or whose ODOM messages all have tv >= 0, are kept. Until the
// first repaired step the raw pose is returned bit for bit.

#include <cstddef>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/odometry.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct ReverseOdometryRepairConfig {
  double min_speed = 0.01;
  double min_step = 1e-3;
  std::size_t min_forward_steps = 20;
  std::size_t reverse_steps_to_trust_poses = 3;
};

template <typename Fields>
void describe(Fields& f, ReverseOdometryRepairConfig& c) {
  f.number("min_speed", c.min_speed, "m/s", at_least(0), "|mean tv| above this is evidence of a direction");
  f.number("min_step", c.min_step, "m", at_least(0), "a forward/backward increment moves at least this");
  f.number("min_forward_steps", c.min_forward_steps, "1", any_value(),
           "forward increments with tv > min_speed before repairing");
  f.number("reverse_steps_to_trust_poses", c.reverse_steps_to_trust_poses, "1", any_value(),
           "backward increments with tv < -min_speed that switch it off");
}

class ReverseOdometryRepair {
 public:
  explicit ReverseOdometryRepair(ReverseOdometryRepairConfig config = {}) : config_(config) {}

  /// An ODOM message between two scans: only its tv is used.
  void observe(const OdometryReading& reading);
  /// The repaired pose for a scan whose (raw) odometry pose is T_odom_robot: the raw pose itself
  /// until the first repaired step, then the raw pose behind the accumulated correction.
  SE2 repair(const SE2& T_odom_robot);
  /// Increments repaired so far: some or all of their travel was reversing (s < 1).
  std::size_t reversed_steps() const { return reversed_steps_; }
  /// True once the log has shown poses that record reversing (no more repairs).
  bool poses_record_reversing() const { return backward_steps_ >= config_.reverse_steps_to_trust_poses; }

 private:
  ReverseOdometryRepairConfig config_;
  bool started_ = false;
  SE2 previous_raw_;
  bool corrected_ = false;  // a step has been repaired: the output is correction_ * raw
  SE2 correction_;
  double tv_sum_ = 0.0;      // since the pose last moved
  double tv_abs_sum_ = 0.0;
  std::size_t tv_count_ = 0;
  std::size_t forward_steps_ = 0;   // mean tv > min_speed, the pose moving forward
  std::size_t backward_steps_ = 0;  // mean tv < -min_speed, the pose moving backwards
  std::size_t reversed_steps_ = 0;
};

}  // namespace slam2d
