// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The laser chain of a sensor log, and the odometry moved in time along it.
//
// The laser chain is the odometry pose written beside every measurement (a laser line that
// carries poses, TRUEPOS), in file order: what every method reads as "the odometry at this scan".
// (A CARMEN log samples the odometry twice, also in its ODOM lines: sim/fault_injection.hpp. The
// ODOM chain is left alone here: no method reads it, and in the SLAM-corrected logs it is not
// even the same odometry.) The chain is smooth in file order, not always in its stamps: Intel's
// step back. So the chain's pose at a time is found by walking from a message's own place in the
// chain, forward or back in file order, to the first pair of neighbours whose stamps bracket that
// time, and interpolating between them (linear in x, y and the shorter way round in heading).
// Beyond either end of the chain the end pose is held. The walk stops after kMaxChainWalk entries
// (a log whose stamps do not advance, as Örebro's all-zero ones, holds the pose reached).
//
// Shifting the odometry in time (shift_scan_odometry) is the one operation behind both the
// compensation of an odometry clock that runs ahead of the laser (io/log_reader.hpp,
// registration/odometry_time_offset.hpp) and the tests that make such a log.

#include <cstddef>
#include <vector>

#include "slam2d/core/se2.hpp"
#include "slam2d/core/sensor_log.hpp"

namespace slam2d {

/// Entries walked at most when looking for a stamp along the chain.
inline constexpr std::size_t kMaxChainWalk = 4096;

struct ChainPose {
  double stamp = 0.0;         // s
  SE2 pose;                   // T_odom_robot
  std::size_t message = 0;    // index of its message in the log
};

/// The laser chain of `messages` (laser lines with poses and TRUEPOS, in file order).
std::vector<ChainPose> laser_odometry_chain(const std::vector<SensorMessage>& messages);

/// The chain's pose at `stamp`, walking from entry `from` (see above). `chain` must not be empty
/// and `from` must index it.
SE2 chain_pose_at(const std::vector<ChainPose>& chain, std::size_t from, double stamp);

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
