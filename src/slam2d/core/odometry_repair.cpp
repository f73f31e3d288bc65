// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/odometry_repair.hpp"

#include <cmath>

namespace slam2d {

void ReverseOdometryRepair::observe(const OdometryReading& reading) {
  tv_sum_ += reading.tv;
  tv_abs_sum_ += std::abs(reading.tv);
  ++tv_count_;
}

SE2 ReverseOdometryRepair::repair(const SE2& T_odom_robot) {
  const SE2 step = started_ ? previous_raw_.between(T_odom_robot) : SE2();
  const bool moved = step.x() != 0.0 || step.y() != 0.0 || step.theta() != 0.0;
  if (moved && tv_count_ > 0) {
    const double tv = tv_sum_ / static_cast<double>(tv_count_);
    if (tv > config_.min_speed && step.x() > config_.min_step) ++forward_steps_;
    if (tv < -config_.min_speed && step.x() < -config_.min_step) ++backward_steps_;
    const bool tv_trusted = forward_steps_ >= config_.min_forward_steps && 2 * reversed_steps_ <= forward_steps_;
    if (step.x() > 0.0 && tv_sum_ < tv_abs_sum_ && tv_trusted && !poses_record_reversing()) {
      const double share = tv_sum_ / tv_abs_sum_;  // in [-1, 1): the net travel over the travel the pose integrated
      // The repaired pose is correction * raw; a repaired step changes the correction.
      const SE2 previous = corrected_ ? correction_ * previous_raw_ : previous_raw_;
      correction_ = (previous * SE2(share * step.x(), share * step.y(), step.theta())) * T_odom_robot.inverse();
      corrected_ = true;
      ++reversed_steps_;
    }
  }
  if (moved || !started_) {
    tv_sum_ = tv_abs_sum_ = 0.0;
    tv_count_ = 0;
  }
  started_ = true;
  previous_raw_ = T_odom_robot;
  return corrected_ ? correction_ * T_odom_robot : T_odom_robot;
}

}  // namespace slam2d
