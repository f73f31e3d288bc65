// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scan-to-scan odometry with keyframes, as in the ROS wrapper of Censi's CSM
// (laser_scan_matcher, I. Dryanovski and W. Morris, scan_tools): each scan is matched against
// the last keyframe scan, and becomes the new keyframe once the robot has moved
// keyframe_distance or turned keyframe_angle from it (their kf_dist_linear = 0.1 m and
// kf_dist_angular = 10 deg, the defaults here; a leave-one-out check over Intel, ACES and FR079
// is in docs/defaults.md). Matching against a keyframe instead of the previous scan keeps a slow
// or standing robot from integrating the matcher's noise.
//
// The target is a small local map: the keyframe's cloud followed by those of the
// local_map_keyframes - 1 keyframes before it, each moved into the keyframe's sensor frame by the
// poses estimated for them (a keyframe taken because the last one no longer matched starts it
// afresh). A pair of scans implies a small heading bias of its own, the same from any guess and
// for every matcher (docs/methods/pl_icp.md, "Why Intel stays near CSM"); summed over thousands
// of keyframe steps it is the drift. A scan matched against two keyframes at once is held by
// both, so the steps' biases no longer add up one by one: PL-ICP on Intel 0.946 -> 0.668 m, and
// 14 of 18 matcher and log pairs lower (docs/defaults.md, "Scan odometry `local_map_keyframes`").
// Such a target is not in one beam order, so PL-ICP searches it by kd-tree, not projectively:
// 110 against 47 us per match on Intel.
//
// The initial guess is the wheel odometry between the keyframe and the scan when both have it
// (checked increment by increment: core/odometry_guard.hpp),
// moved into the sensor frames with each scan's T_robot_sensor; else a constant-velocity
// prediction (the last relative motion per second, extrapolated over the scan's time step, or
// no motion after a gap longer than max_guess_dt). A match is accepted when it passes the gate
// (all thresholds in ScanOdometryConfig):
//   - the matcher converged (require_convergence),
//   - its inliers are at least min_inlier_fraction of the scan's usable points,
//   - its RMS residual is at most max_residual,
//   - it moved the guess by at most max_correction_distance and max_correction_angle
//     (in the keyframe's sensor frame: the correction is guess^-1 * result).
// Otherwise the guess is taken, a failure is counted and the scan becomes the new keyframe
// (the old one evidently no longer matches): the odometry's increment where the guard trusts it.
// An accepted match and a trusted odometry increment are two measurements of the motion from the
// keyframe, each with its covariance (core/motion_fusion.hpp: the odometry's from its motion
// noise model, whose scale is learnt from their agreement; the match's from the matcher, floored
// and inflated along a degenerate direction: registration/match_fusion.hpp): they are fused by
// information, or, where they disagree beyond their joint uncertainty, the better-conditioned
// one is kept (`fuse_odometry`, off by default). Without odometry the match alone places the scan. Scans with fewer than 3 usable points are not
// matched (a failure; the keyframe stays).
//
// World frame: the first scan's odometry pose T_odom_robot when it is given (so the trajectory
// lives in the log's odometry frame), else the first scan's robot frame.

#include <cstddef>
#include <deque>
#include <functional>
#include <optional>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/odometry_guard.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/registration/match_fusion.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

struct ScanOdometryConfig {
  double keyframe_distance = 0.1;
  double keyframe_angle = 0.17453292519943295;
  std::size_t local_map_keyframes = 2;
  double min_range = 0.0;
  double max_range = 30.0;
  double max_guess_dt = 1.0;
  bool require_convergence = true;
  double min_inlier_fraction = 0.3;
  double max_residual = 0.1;
  double max_correction_distance = 0.5;
  double max_correction_angle = 0.5;
  // Each odometry increment is checked first (core/odometry_guard.hpp); a scan whose increment is
  // not trusted (a stall, a jump) is predicted by constant velocity, and its estimated motion
  // replaces the increment in the odometry the next predictions start from; a catch-up is
  // applied from the scan where the odometry last moved.
  OdometryGuardConfig odometry_guard{};
  // Off by default: over range-noise seeds it did not beat the match alone (docs/methods/pl_icp.md,
  // "Fusion with the odometry").
  bool fuse_odometry = false;
  OdometryNoiseConfig odometry_noise{};
  MatchNoiseConfig match_noise{.floor_translation = 0.005, .floor_rotation = 0.0005};
  double fusion_gate = kMotionGateChi2;
};

template <typename Fields>
void describe(Fields& f, ScanOdometryConfig& c) {
  f.number("keyframe_distance", c.keyframe_distance, "m", at_least(0), "new keyframe once |t| from it reaches this (0: every scan)");
  f.number("keyframe_angle", c.keyframe_angle, "rad", at_least(0), "... or |theta| reaches this (10 deg; 0: every scan)");
  f.number("local_map_keyframes", c.local_map_keyframes, "1", at_least(1),
           "the target is the last this many keyframes' clouds, moved into the newest one's frame (1: the keyframe alone)");
  f.number("min_range", c.min_range, "m", at_least(0), "readings below are dropped");
  f.number("max_range", c.max_range, "m", greater_than(0),
           "> min_range; readings at or beyond are dropped (a SICK LMS is reliable to ~30 m, and logs report no-return as a far reading: 50 m in ACES)");
  f.number("max_guess_dt", c.max_guess_dt, "s", greater_than(0), "no constant-velocity extrapolation over longer gaps");
  f.flag("require_convergence", c.require_convergence, "gate: the matcher must report converged");
  f.number("min_inlier_fraction", c.min_inlier_fraction, "1", between(0, 1), "gate on inliers / usable points of the scan");
  f.number("max_residual", c.max_residual, "m", greater_than(0), "gate on the matcher's RMS residual");
  f.number("max_correction_distance", c.max_correction_distance, "m", greater_than(0), "gate on |t| of guess^-1 * result (CSM ROS: 0.5)");
  f.number("max_correction_angle", c.max_correction_angle, "rad", greater_than(0), "gate on |theta| of guess^-1 * result");
  f.section("odometry_guard", c.odometry_guard, "which odometry increments are trusted (core/odometry_guard.hpp)");
  f.flag("fuse_odometry", c.fuse_odometry, "fuse an accepted match with the trusted odometry increment (false: the match alone)");
  f.section("odometry_noise", c.odometry_noise, "the odometry's motion noise model (core/motion_fusion.hpp)");
  f.section("match_noise", c.match_noise, "the match's covariance for the fusion (registration/match_fusion.hpp)");
  f.number("fusion_gate", c.fusion_gate, "1", greater_than(0),
           "chi-square (3 dof) beyond which odometry and match disagree and the better-conditioned one wins");
}

/// Throws Error for values outside the ranges above.
void validate(const ScanOdometryConfig& config);

struct ScanOdometryStats {
  std::size_t scans = 0;           // added
  std::size_t matches = 0;         // matcher calls
  std::size_t failures = 0;        // scans whose pose came from the guess (gate failed, or too few points)
  std::size_t keyframes = 0;       // keyframes taken, the first scan included
  std::size_t total_iterations = 0;  // sum of MatchResult::iterations
  double matcher_seconds = 0.0;    // s, wall time spent inside the matcher
  MotionFusionStats fusion;              // accepted matches fused with the odometry, and the disagreements' winners
};

/// A scan-to-scan match moved from the sensor frames into the robots' frames:
///   T_target_source' = T_robot_target_sensor * T_target_source * T_robot_source_sensor^-1,
/// its covariance propagated to first order (J cov J^T, J the derivative of (x, y, theta) of that
/// product by those of T_target_source) and its weak direction mapped by J. The rest is kept.
MatchResult match_between_robots(const MatchResult& match, const SE2& T_robot_target_sensor,
                                 const SE2& T_robot_source_sensor);

class ScanOdometry {
 public:
  /// Throws Error for an empty matcher or an invalid config.
  explicit ScanOdometry(Matcher matcher, const ScanOdometryConfig& config = {});

  /// Adds the next scan (with the robot's odometry pose T_odom_robot at it, if known) and
  /// returns the estimated T_world_robot at the scan.
  SE2 add(const LaserScan& scan, std::optional<SE2> odom_pose = std::nullopt);

  const Trajectory& trajectory() const { return trajectory_; }  // one pose per scan, stamped
  const ScanOdometryStats& stats() const { return stats_; }
  const MatchResult& last_match() const { return last_match_; }  // of the last matched scan
  bool last_accepted() const { return last_accepted_; }          // whether the last scan's match passed the gate
  bool last_matched() const { return last_matched_; }  // whether the matcher ran for the last scan added
  /// T_robot_sensor of the keyframe the last matched scan was matched against (the match's target):
  /// with it, match_between_robots(last_match(), ..., scan.T_robot_sensor) is the keyframe-to-scan estimate.
  const SE2& last_target_T_robot_sensor() const { return last_target_T_robot_sensor_; }
  /// The index (0-based, in the order add() was called) of the keyframe scan the last matched scan
  /// was matched against: consecutive keyframes chain the trajectory, so their matches carry its drift.
  std::size_t last_target_index() const { return last_target_index_; }
  const ScanOdometryConfig& config() const { return config_; }
  const OdometryGuardStats& odometry_stats() const { return odometry_guard_.stats(); }
  const OdometryNoiseModel& odometry_noise() const { return odometry_noise_; }

 private:
  struct Keyframe {
    PointCloud2 cloud;            // sensor frame, beam order
    SE2 T_world_robot;
    SE2 T_robot_sensor;
    std::optional<SE2> odom_pose;
    std::size_t index = 0;        // of the scan, in the order add() was called
  };

  PointCloud2 usable_cloud(const LaserScan& scan) const;
  SE2 predict(double stamp, const std::optional<SE2>& odom_pose) const;  // T_keyframe_robot
  bool passes_gate(const MatchResult& match, const SE2& guess, std::size_t points) const;
  SE2 fuse_with_odometry(const SE2& odometry, const SE2& T_robot_sensor);  // T_keyframe_robot
  void update_velocity(double stamp, const SE2& T_world_robot);

  Matcher matcher_;
  ScanOdometryConfig config_;
  OdometryGuard odometry_guard_;
  OdometryNoiseModel odometry_noise_;
  // The odometry with each untrusted increment replaced by the estimated motion: correction * raw
  // (none until the first untrusted increment, so clean odometry is used exactly as logged).
  std::optional<SE2> odometry_correction_;
  SE2 guarded_previous_;  // the guarded odometry pose of the last scan
  SE2 guarded_moved_;     // ... of the last scan whose odometry pose moved
  void take_keyframe(Keyframe keyframe, bool keep_local_map);
  std::optional<Keyframe> keyframe_;
  std::deque<Keyframe> earlier_keyframes_;  // the local map's older keyframes, newest first
  PointCloud2 target_;                      // the local map in the keyframe's sensor frame
  SE2 T_world_previous_;          // the last scan's pose
  double previous_stamp_ = 0.0;   // s
  std::optional<SE2> velocity_;   // the last relative motion (robot frame) per velocity_dt_
  double velocity_dt_ = 0.0;      // s
  Trajectory trajectory_;
  ScanOdometryStats stats_;
  MatchResult last_match_;
  bool last_accepted_ = false;
  bool last_matched_ = false;
  SE2 last_target_T_robot_sensor_;
  std::size_t last_target_index_ = 0;
};

}  // namespace slam2d
