#include "slam2d/localization/odometry_repair.hpp"

namespace slam2d {

void ReverseOdometryRepair::observe(const OdometryReading& reading) {
  tv_sum_ += reading.tv;
  ++tv_count_;
}

SE2 ReverseOdometryRepair::repair(const SE2& T_odom_robot) {
  if (started_ && tv_count_ > 0 && tv_sum_ < 0.0) {
    const SE2 step = previous_raw_.between(T_odom_robot);
    if (step.x() > 0.0) {
      // The repaired pose is correction * raw; a mirrored step changes the correction.
      const SE2 previous = corrected_ ? correction_ * previous_raw_ : previous_raw_;
      correction_ = (previous * SE2(-step.x(), -step.y(), step.theta())) * T_odom_robot.inverse();
      corrected_ = true;
      ++reversed_steps_;
    }
  }
  started_ = true;
  previous_raw_ = T_odom_robot;
  tv_sum_ = 0.0;
  tv_count_ = 0;
  // Until the first mirrored step the raw pose is returned bit for bit.
  return corrected_ ? correction_ * T_odom_robot : T_odom_robot;
}

}  // namespace slam2d
