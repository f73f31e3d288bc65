#pragma once
// Repair of odometry that integrates reverse driving as forward driving.
//
// In the FR079 raw log (fr079.clf.gz) the ODOM velocity tv is negative while the robot backs up
// (e.g. 197.9-200.4 s after the first scan: tv = -0.5 m/s), yet the odometry pose x, y advances
// along the heading: the pose integrates |tv|. The relations of Kuemmerle et al. 2009 and the
// SLAM-corrected log agree that the robot moved backwards there; 294 of the 4934 scan-to-scan
// odometry steps of that log are affected. Intel and ACES have none.
//
// ReverseOdometryRepair rebuilds the odometry from the scan-to-scan increments, mirroring the
// translation of an increment (dx, dy, dtheta) -> (-dx, -dy, dtheta) when the mean tv of the ODOM
// messages since the previous scan is negative while the increment moves forward (dx > 0).
// Increments without ODOM messages, or whose direction already agrees with tv, are kept.

#include <cstddef>

#include "slam2d/core/odometry.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

class ReverseOdometryRepair {
 public:
  /// An ODOM message between two scans: only its tv is used.
  void observe(const OdometryReading& reading);
  /// The repaired pose for a scan whose (raw) odometry pose is T_odom_robot: the raw pose itself
  /// until the first mirrored step, then the raw pose behind the accumulated correction.
  SE2 repair(const SE2& T_odom_robot);
  /// Increments mirrored so far.
  std::size_t reversed_steps() const { return reversed_steps_; }

 private:
  bool started_ = false;
  SE2 previous_raw_;
  bool corrected_ = false;  // a step has been mirrored: the output is correction_ * raw
  SE2 correction_;
  double tv_sum_ = 0.0;
  std::size_t tv_count_ = 0;
  std::size_t reversed_steps_ = 0;
};

}  // namespace slam2d
