// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// An odometry chain of a sensor log, and the odometry moved in time along it: the one home of
// "the odometry pose at a shifted time", behind the compensation of an odometry clock that runs
// ahead of the laser (io/log_reader.hpp), its estimate (registration/odometry_time_offset.hpp)
// and the fault that makes such a log (sim/fault_injection.hpp, odom-shift).
//
// A chain is one sequence of odometry samples in file order. The laser chain is the odometry pose
// written beside every measurement (a laser line that carries poses, TRUEPOS): what every method
// reads as "the odometry at this scan". (A CARMEN log samples the odometry a second time, in its
// ODOM lines; the fault moves that chain too, the compensation leaves it alone: no method reads it,
// and in the SLAM-corrected logs it is not even the same odometry.)
//
// A chain is smooth in file order, not always in its stamps: Intel's step back (a line written up
// to 0.9 s late, the lines after it on time again). So the chain's clock is its stamps lowered to
// be non-decreasing, each to the smallest stamp at or after it: a late sample keeps its place on
// the path, where sorting by stamp would put it among later poses and make the path zigzag. The
// pose at a time is then interpolated between the two samples around it (linear in x and y, the
// shorter way round in heading), found by binary search on the side of the sample asked from, and
// held beyond either end. A log whose stamps never advance (Örebro's are all 0) gives the end poses.

#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/se2.hpp"
#include "slam2d/core/sensor_log.hpp"

namespace slam2d {

struct ChainSample {
  std::size_t message = 0;  // index of its message in the log
  double stamp = 0.0;       // s; in a chain, lowered to be non-decreasing (see above)
  SE2 pose;                 // T_odom_robot
};

/// Odometry samples in file order, on the chain's clock (stamps lowered to be non-decreasing).
class OdometryChain {
 public:
  OdometryChain() = default;
  /// `samples` in file order, with their stamps as logged.
  explicit OdometryChain(std::vector<ChainSample> samples);

  /// The pose at `time` (s, on the chain's clock), seen from sample k: between the two samples
  /// around `time` on k's side, so time = stamp of k gives k's own pose whatever samples share its
  /// stamp; the end poses beyond the chain. k must index the chain.
  SE2 at(std::size_t k, double time) const;

  /// Sample k's odometry moved by `by` s: the pose at its own stamp + by (by > 0: later).
  SE2 shifted(std::size_t k, double by) const { return at(k, samples_[k].stamp + by); }

  std::size_t size() const { return samples_.size(); }
  bool empty() const { return samples_.empty(); }
  const ChainSample& operator[](std::size_t k) const { return samples_[k]; }

 private:
  std::vector<ChainSample> samples_;
};

/// Whether a message belongs to the laser chain: a laser line with poses, or TRUEPOS.
bool in_laser_chain(const SensorMessage& message);

/// Message `index`'s sample of the laser chain; none when it is not in the chain.
std::optional<ChainSample> chain_sample(std::size_t index, const SensorMessage& message);

/// The laser chain of `messages` (laser lines with poses and TRUEPOS, in file order).
OdometryChain laser_odometry_chain(const std::vector<SensorMessage>& messages);

/// Every laser-chain message's odometry pose becomes the chain's pose at its own stamp + `by`
/// (s): the odometry of `by` s later. A laser line's estimated pose follows when it repeated the
/// odometry (raw logs). ODOM and IMU messages are kept. Returns the number of poses changed.
std::size_t shift_scan_odometry(std::vector<SensorMessage>& messages, double by);

/// The odometry pose a message carries (laser line, ODOM or TRUEPOS); IMU messages have none.
SE2 odometry_pose(const SensorMessage& message);

/// Sets it; a laser line's estimated pose follows it when it repeated it, and a ROBOTLASER1's
/// laser pose keeps its mounting on the robot. IMU messages are left alone.
void set_odometry_pose(SensorMessage& message, const SE2& pose);

}  // namespace slam2d
