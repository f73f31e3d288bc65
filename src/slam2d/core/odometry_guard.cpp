// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/odometry_guard.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

// Writes `value` into a ring of the last `capacity` values, `seen` values having been written.
void put(std::vector<double>& ring, std::size_t seen, std::size_t capacity, double value) {
  if (ring.size() < capacity) {
    ring.push_back(value);
  } else {
    ring[seen % capacity] = value;
  }
}

// The value at `index` of `values` sorted (its own copy, partly sorted).
double nth_value(std::vector<double> values, std::size_t index) {
  const auto nth = values.begin() + static_cast<std::ptrdiff_t>(index);
  std::nth_element(values.begin(), nth, values.end());
  return *nth;
}

}  // namespace

void validate(const OdometryGuardConfig& config) {
  check_fields(config, "OdometryGuardConfig");
  check(config.max_startup_time >= config.min_time_step, "OdometryGuardConfig: max_startup_time must be >= min_time_step");
  check(config.min_step_history <= config.step_history, "OdometryGuardConfig: min_step_history must be <= step_history");
}

OdometryGuard::OdometryGuard(const OdometryGuardConfig& config) : config_(config) { validate(config_); }

OdometryCheck OdometryGuard::check(double stamp, const SE2& T_odom_robot) {
  OdometryCheck result;
  if (!last_pose_) {
    result.first = true;
  } else {
    result.increment = last_pose_->between(T_odom_robot);
    result.dt = stamp - last_stamp_;
    result.gap = result.dt > config_.gap;
    stats_.gaps += result.gap ? 1 : 0;
    const std::size_t stalls = stats_.stalls;
    // How long the pose had stood still: up to this scan if it is still frozen, else up to the last.
    const double stood = (is_frozen(result.increment) ? stamp : last_stamp_) - moved_at_;
    const bool restarted = at_origin(T_odom_robot) && !at_origin(*last_pose_);
    // The motion since the reference: what a catch-up carries (OdometryCheck::moved).
    const Step since_reference{reference_pose_->between(T_odom_robot), stamp - reference_stamp_ + lag_allowance_};
    if (config_.enabled) {
      result.fault = classify({result.increment, result.dt + lag_allowance_}, since_reference, stood, restarted);
      if (result.fault == OdometryFault::kCatchUp) result.increment = since_reference.increment;
    }
    result.confirm = config_.enabled && result.trusted() && is_moving(result.increment) && pauses(result.dt);
    result.burst = config_.enabled && result.trusted() && !is_moving(result.increment) && bursts(result.dt);
    remember_time_step(result.dt);
    stats_.pause_confirmations += result.confirm ? 1 : 0;
    stats_.burst_checks += result.burst ? 1 : 0;
    result.stall_start = stats_.stalls > stalls;
    result.hold_map = result.fault == OdometryFault::kStall && stood <= config_.max_held_stall;
    // After a gap the odometry pose of the next scan may lag (logged before the gap's motion was
    // integrated): the increment after it may still carry that motion.
    lag_allowance_ = result.gap ? result.dt : 0.0;
    ++stats_.checks;
  }
  const bool changed = result.first || !is_frozen(result.increment);
  if (changed) moved_at_ = stamp;
  // A jumped reading is no reference (unless the odometry restarted: then its frame is new for good).
  result.moved = changed && !jumped_;
  if (result.moved) {
    reference_pose_ = T_odom_robot;
    reference_stamp_ = stamp;
  }
  last_pose_ = T_odom_robot;
  last_stamp_ = stamp;
  return result;
}

bool OdometryGuard::is_frozen(const SE2& increment) const {
  return increment.translation().norm() <= config_.frozen_translation &&
         std::abs(increment.theta()) <= config_.frozen_rotation;
}

// The median of the last step_history time steps; none while fewer than min_step_history are known.
std::optional<double> OdometryGuard::median_time_step() const {
  if (time_steps_.size() < config_.min_step_history) return std::nullopt;
  return nth_value(time_steps_, time_steps_.size() / 2);
}

// A pause in the log's rhythm: a time step more than confirm_pause times the median of the last
// step_history ones (a log that scans every two seconds has no pause at two seconds; one that
// scans every 0.1 s has one at 0.8 s). Asked only of an increment that could be confirmed.
bool OdometryGuard::pauses(double dt) const {
  if (config_.confirm_pause <= 0.0) return false;
  const std::optional<double> median = median_time_step();
  return median && dt > config_.confirm_pause * *median;
}

// A burst in the log's rhythm: a time step less than the median over confirm_burst (scans stamped
// as a logger read them after a pause, 1 ms apart). Asked only of an increment that stood.
bool OdometryGuard::bursts(double dt) const {
  if (config_.confirm_burst <= 0.0) return false;
  const std::optional<double> median = median_time_step();
  return median && dt * config_.confirm_burst < *median;
}

// Every positive time step joins the history, after the test.
void OdometryGuard::remember_time_step(double dt) {
  if (dt > 0.0) put(time_steps_, time_steps_seen_++, config_.step_history, dt);
}

bool OdometryGuard::is_moving(const SE2& increment) const {
  return increment.translation().norm() > config_.moving_translation || std::abs(increment.theta()) > config_.moving_rotation;
}

// The state machine of the header: stall (frozen after motion) until the pose moves; the return
// of an odometry that jumped (a catch-up from the reading before the jump) when it is back within
// the bounds of that reading; a catch-up when it moves after a stall, or after a rest of
// stall_duration or more by more than a robot driving off could (it may have moved unseen); a jump
// when it restarted onto the origin or is out of bounds. `step` is the increment from the last
// scan over its time (plus a gap's lag allowance), `since_reference` the motion since the
// reference reading (OdometryCheck::moved) over the time since.
OdometryFault OdometryGuard::classify(const Step& step, const Step& since_reference, double stood, bool restarted) {
  const SE2& increment = step.increment;
  if (is_frozen(increment)) {
    // At rest "no motion" is true; and a pose repeated over less than stall_duration may be an
    // odometry slower than the scanner.
    if (!stalled_ && (!was_moving_ || stood < config_.stall_duration)) return OdometryFault::kNone;
    if (!stalled_) ++stats_.stalls;
    stalled_ = true;
    ++stats_.stalled_scans;
    return OdometryFault::kStall;
  }
  const bool moving = is_moving(increment);
  if (jumped_ && !restarted && since_reference.dt > 0.0 && !exceeds_bounds(since_reference.increment, since_reference.dt)) {
    jumped_ = false;
    was_moving_ = moving;
    ++stats_.catch_ups;
    ++stats_.returns;
    return OdometryFault::kCatchUp;
  }
  jumped_ = false;
  const bool catch_up = stalled_ || (stood >= config_.stall_duration && exceeds_startup(increment, step.dt));
  if (restarted || (catch_up && exceeds_bounds(since_reference.increment, since_reference.dt))) {
    // Onto the origin itself, or more than the robot could have moved since the pose last
    // changed: not motion or a catch-up but a jump (an odometry that restarted from its origin).
    stalled_ = false;
    was_moving_ = false;
    jumped_ = !restarted;
    ++stats_.jumps;
    return OdometryFault::kJump;
  }
  if (catch_up) {
    stalled_ = false;
    was_moving_ = moving;
    ++stats_.catch_ups;
    return OdometryFault::kCatchUp;
  }
  if (exceeds_bounds(increment, step.dt)) {
    jumped_ = true;
    ++stats_.jumps;
    return OdometryFault::kJump;
  }
  was_moving_ = moving;
  if (moving) remember_step(increment);
  return OdometryFault::kNone;
}

bool OdometryGuard::at_origin(const SE2& T_odom_robot) const {
  return T_odom_robot.translation().norm() <= config_.restart_translation &&
         std::abs(T_odom_robot.theta()) <= config_.restart_rotation;
}

bool OdometryGuard::exceeds_startup(const SE2& increment, double dt) const {
  const double step = std::clamp(dt, config_.min_time_step, config_.max_startup_time);
  return increment.translation().norm() > 0.5 * config_.startup_acceleration * step * step ||
         std::abs(increment.theta()) > 0.5 * config_.startup_angular_acceleration * step * step;
}

// Beyond what the robot could have moved in dt (when the stamps carry speed) and beyond the log's
// own steps, in translation or in rotation; an increment the speed bounds alone would have called
// a jump is counted speedless.
bool OdometryGuard::exceeds_bounds(const SE2& increment, double dt) {
  const double step = std::max(dt, config_.min_time_step);
  const double translation = increment.translation().norm();
  const double rotation = std::abs(increment.theta());
  const bool fast = translation > config_.max_speed * step + config_.jump_translation_slack;
  const bool fast_turn = rotation > config_.max_turn_rate * step + config_.jump_rotation_slack;
  if (!fast && !fast_turn) return false;
  if (dt > 0.0 && ((fast && beyond_steps(translation, step_translations_)) ||
                   (fast_turn && beyond_steps(rotation, step_rotations_)))) {
    return true;
  }
  ++stats_.speedless;
  return false;
}

// More than step_factor times the 90th percentile of the recent moving increments' `steps`; true
// while too few are known (the speed bounds alone judge then).
bool OdometryGuard::beyond_steps(double value, const std::vector<double>& steps) const {
  if (config_.step_factor <= 0.0 || steps.size() < config_.min_step_history) return true;
  const auto p90 = static_cast<std::size_t>(0.9 * static_cast<double>(steps.size() - 1));
  return value > config_.step_factor * nth_value(steps, p90);
}

void OdometryGuard::remember_step(const SE2& increment) {
  put(step_translations_, steps_seen_, config_.step_history, increment.translation().norm());
  put(step_rotations_, steps_seen_, config_.step_history, std::abs(increment.theta()));
  ++steps_seen_;
}

}  // namespace slam2d
