// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The odometry layer every method reads wheel odometry through: it checks each scan-to-scan
// odometry increment before a method trusts it, so that no motion is ever counted twice.
//
// The fault it exists for (a held-out log of the Kuemmerle et al. 2009 benchmark): the odometry
// froze for about one second (five scans with an identical odometry pose) while the robot kept
// moving, then jumped by 0.86 m and 0.85 rad in one step. A method that trusts every increment
// follows the robot by scan matching during the freeze, then adds the jump on top: the motion of
// the freeze is counted twice. The checks, per increment between two consecutive scans:
//  - stall: the odometry pose did not change at all (to `frozen_translation` / `frozen_rotation`)
//    for at least `stall_duration` while the increment before it moved (more than
//    `moving_translation` / `moving_rotation`): an encoder or driver that stopped reporting, not a
//    robot that stopped. A robot comes to rest through smaller and smaller increments, so a pose
//    frozen right after a moving one is taken as a stall and stays one until the pose moves
//    again. Frozen increments after small ones (a robot at rest) are trusted: they say "no
//    motion", which is true; so are those within stall_duration of the last change (an odometry
//    slower than the scanner repeats its pose; Intel has scans 1 ms apart).
//  - catch-up: the first increment after the pose stood still for stall_duration or more: after a
//    stall it carries the motion of the whole stall; after a rest, any motion the robot made
//    while the odometry froze (a freeze that began at rest cannot be told from the rest itself).
//    After a rest only an increment larger than a robot starting from rest could make in the time
//    step (half of `startup_acceleration` / `startup_angular_acceleration` times dt squared, dt
//    clamped to [min_time_step, max_startup_time]) is a catch-up: the first increment of a robot
//    that simply drives off again is trusted. Over a longer step a freeze cannot be told from a
//    robot that drove off by the increment's size (Intel's scans are up to 2 s apart), so the bound
//    stops growing there. A method applies a catch-up from its estimate at the scan where the
//    pose last moved (OdometryCheck::moved), which is right either way. A catch-up larger than
//    the robot could have moved since the pose last changed (the jump bounds below over that
//    time) is a jump instead: an odometry that restarted from its origin while the robot stood.
//  - return: the first increment that is not frozen after a jump (not a restart), when the motion
//    from the reading before the jump is within the bounds above over the time since: the jump was
//    a reading out of line, a spike, or a stale reading (ACES played backwards: at its 3 s pause the
//    odometry lags, so the increment before the pause turns 1.06 rad in 0.16 s, a jump, and the one
//    across the pause 0.39 rad where the robot turned 1.4). The increment is then a catch-up from
//    the reading before the jump: a jumped reading is not one a catch-up starts from
//    (OdometryCheck::moved is false there). An odometry that jumped for good fails the test and
//    is trusted again from its next increment on.
//  - jump: an increment beyond what the robot could have moved in the time step: more than
//    max_speed * dt + jump_translation_slack or max_turn_rate * dt + jump_rotation_slack, with dt
//    at least min_time_step (stamps of real logs jitter and step back, so short or negative steps
//    must not shrink the bound).
//  - held: a stall's scans within `max_held_stall` seconds of the pose's last change. Within a
//    stall a method places the robot by scan matching alone, which along a corridor does not see
//    it move (ACES with a 10 s stall every 120 s: the robot drives 4 m, Hector's estimate 0.4 m);
//    a map written at such poses is wrong for good, while the catch-up at the stall's end puts
//    the pose right again. So Hector and graph SLAM's tracker write nothing into their maps at
//    held scans and wait for the catch-up (the RBPF does not: one update over a long stall loses
//    its particles on FR079; docs/odometry_guard.md, "Long stalls"). An odometry frozen for
//    longer is taken as lost, and the maps follow the scan matching again (as without odometry).
//    The speed bounds need stamps that carry speed, and some logs have none: stamps all zero, or
//    invented at one second a scan (the SLAM-corrected Orebro log, whose scans lie up to 3.3 m
//    apart). So an increment is a jump only when it also stands out of the log's own steps: more
//    than step_factor times the 90th percentile of the last step_history moving increments
//    (translation or rotation alike; from min_step_history increments on); and an increment whose
//    stamp did not advance (dt <= 0) carries no speed: only the restart test below applies to it.
//    Either case is counted (speedless), and the summary warns of it.
//  - restart: a step onto the odometry origin itself (to `restart_translation` and
//    `restart_rotation`, 1 mm and 1 mrad) from a pose that was not there is a jump whatever its
//    size. A driver or controller that restarts begins again at (0, 0, 0); after a gap of
//    seconds, or near where its last chain began, that step is within the bounds above and
//    would be taken for motion (Intel's restart after a 2.1 s gap: 3.1 m and 2.1 rad, every SLAM
//    method 1.17-1.19 m). A robot that drives back onto its odometry origin to a millimetre and a
//    milliradian loses one increment's prior, no more.
//  - gap: consecutive scans more than `gap` seconds apart (reported; the increment over a gap is
//    checked like any other, against the longer dt). The odometry pose of the first scan after a
//    gap may lag (ACES: the robot turns 1.4 rad during a 3 s gap, the scan after it shows 0.39 rad
//    and the next increment the other 1.06 rad within 0.16 s), so the increment after a gap is
//    bounded over the gap's time too.
//  - confirm: a trusted increment that moved over a pause in the log's rhythm: a time step more
//    than confirm_pause times the median of the last step_history ones, whether or not it is a
//    gap (a log that scans every two seconds has no pause at two seconds, one that scans every
//    0.1 s has one at 0.8 s). Over a pause the odometry at the scan may lag, and an odometry moved
//    in time along the stamps (a compensated clock offset) is interpolated across it: Intel's
//    logger stamped scans as it read them, so a 2.4 s pause is followed by a burst of scans 1 ms
//    apart taken during it, and its odometry 0.6 s ahead put the burst's 1.3 rad on the scan after
//    the pause, where the robot had turned 0.1 rad; shorter pauses (0.8 s, below the gap) did the
//    same with turns of 0.5-0.8 rad. The method matches the scan from the last pose too, which
//    wins with a fit a fifth better (kCompetingStartAdvantage); then it sets
//    OdometryCheck::refuted, and the increment is trusted no more.
//  - burst: a trusted increment that did not move over a time step shorter than the median over
//    confirm_burst: a scan of a burst like Intel's, taken during the pause before it, where the
//    odometry (logged at its own rate, or interpolated along the stamps) stands while the scans
//    turn. The method matches the scan from the last estimated motion repeated too, and refutes
//    the increment as above (Hector: HectorSlam::confirming_start; off, confirm_burst 0, by
//    default and in every other method, graph SLAM's tracker included).
// A stalled, caught-up or jumped increment is not trusted: the method predicts that scan from the
// last pose it trusts and its own motion estimate (each method's docs say how), and the
// odometry is trusted again from the next good increment on. Counts go to summary.json as
// odometry_stalls, odometry_stalled_scans, odometry_catch_ups, odometry_jumps, odometry_gaps,
// odometry_pause_confirmations, odometry_pause_refutations, odometry_burst_checks,
// odometry_burst_refutations.
//
// Defaults: the bounds sit above every increment of the three public logs (Intel, ACES, FR079:
// at most 0.38 m and 1.06 rad between scans, 0.14 m and 0.33 rad at the 99.9th percentile) and
// above what an indoor robot does (2 m/s, 4 rad/s), and below the held-out jump. The startup
// bounds (2 m/s^2, 4 rad/s^2: 0.04 m and 0.08 rad over 0.2 s, at most 0.0625 m and 0.125 rad)
// sit above every first increment after a rest in those logs (154 rests; at most 0.023 m and
// 0.041 rad) and about twice what an indoor robot's acceleration allows.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OdometryGuardConfig {
  bool enabled = true;
  double frozen_translation = 1e-6;
  double frozen_rotation = 1e-6;
  double moving_translation = 0.01;
  double moving_rotation = 0.01;
  double stall_duration = 0.25;
  double max_speed = 2.0;
  double max_turn_rate = 4.0;
  double jump_translation_slack = 0.1;
  double jump_rotation_slack = 0.2;
  double min_time_step = 0.1;
  double startup_acceleration = 2.0;
  double startup_angular_acceleration = 4.0;
  double max_startup_time = 0.25;  // >= min_time_step
  double gap = 1.0;
  double restart_translation = 1e-3;
  double restart_rotation = 1e-3;
  // 30 s of driving is about what a catch-up's odometry still brings within the matchers' reach.
  double max_held_stall = 30.0;
  // The log's own steps: a real jump (0.86 m at 10 Hz in the held-out log) is 8x its neighbours;
  // an invented stamp's step (Orebro, 1 s a scan) at most 3.1x the log's median.
  double step_factor = 4.0;
  std::size_t step_history = 50;
  std::size_t min_step_history = 3;
  // An increment over a pause in the log's rhythm (OdometryCheck::confirm).
  double confirm_pause = 5.0;
  // A standing increment within a burst of scans (OdometryCheck::burst); off but in Hector, the
  // one method with a use for it (HectorSlamConfig).
  double confirm_burst = 0.0;
};

template <typename Fields>
void describe(Fields& f, OdometryGuardConfig& c) {
  f.flag("enabled", c.enabled, "false: every increment is trusted (the raw odometry)");
  f.number("frozen_translation", c.frozen_translation, "m", at_least(0),
           "an increment this small in both parts is \"frozen\"");
  f.number("frozen_rotation", c.frozen_rotation, "rad", at_least(0), "... and turning this little");
  f.number("moving_translation", c.moving_translation, "m", at_least(0),
           "an increment larger than this (or the rotation below) means the robot was moving");
  f.number("moving_rotation", c.moving_rotation, "rad", at_least(0), "... or turning more than this");
  f.number("stall_duration", c.stall_duration, "s", at_least(0), "a frozen pose is a stall once it stood this long");
  f.number("max_speed", c.max_speed, "m/s", greater_than(0), "faster increments are jumps");
  f.number("max_turn_rate", c.max_turn_rate, "rad/s", greater_than(0), "faster-turning increments are jumps");
  f.number("jump_translation_slack", c.jump_translation_slack, "m", at_least(0), "added to the translation bound");
  f.number("jump_rotation_slack", c.jump_rotation_slack, "rad", at_least(0), "added to the rotation bound");
  f.number("min_time_step", c.min_time_step, "s", greater_than(0), "dt used for the bounds is at least this");
  f.number("startup_acceleration", c.startup_acceleration, "m/s^2", greater_than(0), "a robot driving off from rest");
  f.number("startup_angular_acceleration", c.startup_angular_acceleration, "rad/s^2", greater_than(0),
           "a robot turning off from rest");
  f.number("max_startup_time", c.max_startup_time, "s", greater_than(0),
           "the startup bound's longest dt (>= min_time_step)");
  f.number("gap", c.gap, "s", greater_than(0), "scans further apart are a gap");
  f.number("restart_translation", c.restart_translation, "m", at_least(0),
           "a step onto the odometry origin to within this (and restart_rotation), from a pose that was not "
           "there, is a restart (a jump) whatever its size");
  f.number("restart_rotation", c.restart_rotation, "rad", at_least(0), "see restart_translation");
  f.number("max_held_stall", c.max_held_stall, "s", at_least(0),
           "a stall this young is waited out (OdometryCheck::hold_map); 0 holds nothing");
  f.number("step_factor", c.step_factor, "1", at_least(0),
           "a jump is also more than this times the 90th percentile of the recent moving increments (0: off)");
  f.number("step_history", c.step_history, "1", at_least(1), "moving increments that percentile is taken over");
  f.number("min_step_history", c.min_step_history, "1", at_least(1),
           "moving increments needed before the step test applies (<= step_history)");
  f.number("confirm_pause", c.confirm_pause, "1", at_least(0),
           "an increment that moved over a time step longer than this times the median one is confirmed by the "
           "scans against the last pose (0: none)");
  f.number("confirm_burst", c.confirm_burst, "1", at_least(0),
           "an increment that did not move over a time step shorter than the median one over this is confirmed by "
           "the scans against the last motion repeated (0: none; Hector's matcher alone has a use for it)");
}

/// Throws Error for out-of-range values.
void validate(const OdometryGuardConfig& config);

/// A method that matches a scan whose increment is not trusted from two starts (its prediction and
/// a competing one, e.g. the last pose against a catch-up: HectorSlam::untrusted_starts,
/// RbpfSlam::corrected_odometry) keeps the competing start only when its fit costs less than this
/// share of the prediction's: the prediction rests on the motion seen, the other on a guess.
inline constexpr double kCompetingStartAdvantage = 0.8;

enum class OdometryFault : std::uint8_t { kNone, kStall, kCatchUp, kJump };

/// The verdict on one scan's odometry increment.
struct OdometryCheck {
  SE2 increment;                        // T_previous_current from the raw odometry (identity at the first scan)
  double dt = 0.0;                      // s, stamp minus the previous scan's (0 at the first)
  OdometryFault fault = OdometryFault::kNone;
  bool gap = false;                     // dt > config.gap
  bool first = false;                   // the first scan: nothing to check
  bool stall_start = false;             // the first increment of a stall
  bool moved = false;                   // the pose changed (or the first scan), not by a jump: a later catch-up
                                        // starts here (its increment is the motion since)
  bool hold_map = false;                // a stall within max_held_stall: write no map at this scan, wait for the catch-up
  bool confirm = false;                 // trusted, moved over a pause: the scans confirm it against the last pose
  bool burst = false;                   // trusted, stood within a burst: the scans confirm it against the last motion
  bool refuted = false;                 // set by the method: the scans refuted it (the last pose won)
  bool trusted() const { return fault == OdometryFault::kNone && !refuted; }
};

struct OdometryGuardStats {
  std::size_t checks = 0;
  std::size_t stalls = 0;          // stall episodes (runs of frozen increments after motion)
  std::size_t stalled_scans = 0;   // increments inside them
  std::size_t catch_ups = 0;
  std::size_t returns = 0;         // of those, an odometry back after a jump (a spike or a stale reading)
  std::size_t jumps = 0;
  std::size_t gaps = 0;
  std::size_t speedless = 0;       // increments beyond the speed bounds that the stamps could not judge
                                   // (dt <= 0) or that stood within the log's own steps
  std::size_t pause_confirmations = 0;  // OdometryCheck::confirm
  std::size_t pause_refutations = 0;    // of those, the ones the method's match refuted (count_refutation)
  std::size_t burst_checks = 0;         // OdometryCheck::burst
  std::size_t burst_refutations = 0;    // of those, the ones the method's match refuted
  std::size_t untrusted() const { return stalled_scans + catch_ups + jumps; }
};

class OdometryGuard {
 public:
  explicit OdometryGuard(const OdometryGuardConfig& config = {});

  /// Checks the odometry pose T_odom_robot of the next scan (stamped `stamp`) against the previous one.
  OdometryCheck check(double stamp, const SE2& T_odom_robot);

  const OdometryGuardStats& stats() const { return stats_; }
  /// The method's match refuted the increment `check` it was asked to confirm (OdometryCheck::refuted).
  void count_refutation(const OdometryCheck& check) { ++(check.burst ? stats_.burst_refutations : stats_.pause_refutations); }
  const OdometryGuardConfig& config() const { return config_; }

 private:
  struct Step {
    SE2 increment;
    double dt = 0.0;  // s
  };
  OdometryFault classify(const Step& step, const Step& since_reference, double stood, bool restarted);
  bool at_origin(const SE2& T_odom_robot) const;
  bool is_frozen(const SE2& increment) const;
  bool is_moving(const SE2& increment) const;
  std::optional<double> median_time_step() const;
  bool pauses(double dt) const;
  bool bursts(double dt) const;
  void remember_time_step(double dt);
  bool exceeds_startup(const SE2& increment, double dt) const;
  bool exceeds_bounds(const SE2& increment, double dt);
  bool beyond_steps(double value, const std::vector<double>& steps) const;
  void remember_step(const SE2& increment);

  OdometryGuardConfig config_;
  std::optional<SE2> last_pose_;
  double last_stamp_ = 0.0;
  double moved_at_ = 0.0;    // s, stamp of the last scan whose pose differed from the one before
  std::optional<SE2> reference_pose_;  // the odometry pose at the last scan that moved (OdometryCheck::moved)
  double reference_stamp_ = 0.0;       // s, its stamp
  bool jumped_ = false;      // the last increment that was not frozen jumped (not a restart): the reference is before it
  bool was_moving_ = false;  // the last trusted increment moved
  bool stalled_ = false;     // inside a stall
  double lag_allowance_ = 0.0;  // s, added to the next dt: the length of a gap just passed
  std::vector<double> step_translations_;  // m, the last step_history moving increments (a ring)
  std::vector<double> step_rotations_;     // rad, their |rotation|
  std::size_t steps_seen_ = 0;
  std::vector<double> time_steps_;  // s, the last step_history positive time steps (a ring)
  std::size_t time_steps_seen_ = 0;
  OdometryGuardStats stats_;
};

}  // namespace slam2d
