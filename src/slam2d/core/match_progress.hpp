// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The scan-matched motion since the last map update against the guarded odometry's over the same
// scans: where the odometry, every increment of it trusted, moved a multiple of the map update
// distance and the matched motion fell short of it by more than 3 sigma of the odometry's own
// translation noise, the odometry refutes the matches. A match can be held back where nothing in
// the scan marks the motion but something pulls: along a corridor whose walls end, in the map,
// where the last update's beams reached (the far points are pulled back onto the mapped wall), or
// by phantoms that travel with the robot (mixed pixels a few metres ahead). Held back, the pose
// stays short of the next map update, the map stays as it was, and the pull holds: the robot stands
// still in the map while it drives on. One scan's increment is too short to tell (the odometry's
// noise, the match's slide, each a few centimetres); over several update distances the odometry's
// error is centimetres, the held-back match's the whole stretch.

#include "slam2d/core/se2.hpp"

namespace slam2d {

class MatchProgress {
 public:
  /// At a map update (and at the start): the stretch starts again.
  void restart() {
    odometry_ = SE2();
    trusted_ = true;
  }

  /// This scan's guarded odometry increment, and whether the guard trusted it (a stall, jump,
  /// catch-up or refuted increment leaves the rest of the stretch unjudged).
  void add(const SE2& increment, bool trusted) {
    odometry_ = odometry_ * increment;
    trusted_ = trusted_ && trusted;
  }

  /// The odometry's motion since restart().
  const SE2& odometry() const { return odometry_; }

  /// Whether the odometry refutes `matched`, the matched motion since restart(), as held back: the
  /// odometry, all of it trusted, moved kOverdueUpdates times the method's `update_distance` (a
  /// match that followed it would have updated the map long before), and `matched` is shorter than
  /// it by more than 3 x `sigma_translation` (the odometry's translation sigma over the stretch).
  bool refutes(const SE2& matched, double update_distance, double sigma_translation) const {
    const double distance = odometry_.translation().norm();
    if (!trusted_ || distance < kOverdueUpdates * update_distance) return false;
    return distance - matched.translation().norm() > 3.0 * sigma_translation;
  }

  /// Four update distances. Over one, real odometry and matches disagree by a quarter at times,
  /// the matches right (FR079 over 0.4 m: Hector and graph SLAM's tracker 0.036 -> 1.1-1.3 m over
  /// all relations); over two, Intel with its odometry 0.3 s ahead and three glass sectors lost
  /// (graph SLAM 0.025 -> 0.57 m, Hector 0.63 -> 2.60 m) and the RBPF on FR079's ROS 1 bag (0.056
  /// -> 1.08 m); from three on, none of these is touched (bench/BENCHMARKS.md, "The hospital world").
  static constexpr double kOverdueUpdates = 4.0;

 private:
  SE2 odometry_;
  bool trusted_ = true;
};

}  // namespace slam2d
