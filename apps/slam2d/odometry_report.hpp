// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the odometry guard (core/odometry_guard.hpp) found, as summary.json reports it for every
// method that reads wheel odometry.

#include <fmt/core.h>

#include <optional>
#include <string>
#include <vector>

#include "json.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/odometry_guard.hpp"
#include "slam2d/slam/fusion/odometry_smoothing.hpp"

namespace slam2d::cli {

inline JsonObject odometry_report(const OdometryGuardStats& stats) {
  JsonObject report;
  report.add("odometry_stalls", stats.stalls).add("odometry_stalled_scans", stats.stalled_scans);
  report.add("odometry_catch_ups", stats.catch_ups).add("odometry_returns", stats.returns).add("odometry_jumps", stats.jumps);
  report.add("odometry_gaps", stats.gaps).add("odometry_pause_confirmations", stats.pause_confirmations);
  report.add("odometry_pause_refutations", stats.pause_refutations).add("odometry_burst_checks", stats.burst_checks);
  report.add("odometry_burst_refutations", stats.burst_refutations).add("odometry_speedless", stats.speedless);
  return report;
}

/// The odometry noise model's learnt scales, and from how many agreements.
inline JsonObject odometry_noise_report(const OdometryNoiseModel& noise) {
  JsonObject report;
  report.add("odometry_noise_scale_translation", noise.translation_scale());
  report.add("odometry_noise_scale_rotation", noise.rotation_scale());
  report.add("odometry_noise_observations", noise.observations());
  return report;
}

/// How odometry and scan matching were weighed: the fusions, the disagreements and their winners,
/// and the odometry noise model's learnt scales.
inline JsonObject fusion_report(const MotionFusionStats& stats, const OdometryNoiseModel& noise) {
  JsonObject report;
  report.add("fusion_fused", stats.fused).add("fusion_disagreements", stats.disagreements());
  report.add("fusion_odometry_won", stats.odometry_won).add("fusion_match_won", stats.match_won);
  report.merge(odometry_noise_report(noise));
  return report;
}

/// The odometry's systematic error a method learnt (core/motion_fusion.hpp's OdometryCalibration).
inline JsonObject calibration_report(const OdometryCalibration& calibration) {
  JsonObject report;
  report.add("odometry_calibration_stretches", calibration.observations());
  report.add("odometry_calibration_translation_scale", calibration.translation_scale());
  report.add("odometry_calibration_rotation_scale", calibration.rotation_scale());
  report.add("odometry_calibration_drift_rad_per_m", calibration.drift_per_metre());
  report.add("odometry_calibration_credible", calibration.credible());
  return report;
}

/// What the per-scan smoothing with the odometry found (slam/fusion/odometry_smoothing.hpp): the
/// jitters and drift scales it estimated, the steps it refused, the largest move of a pose.
inline JsonObject smoothing_report(const OdometrySmoothingStats& stats) {
  JsonObject report;
  report.add("applied", stats.applied);
  if (!stats.applied) return report.add("skipped", stats.skipped);
  const auto triple = [](const Eigen::Vector3d& v) { return std::vector<double>{v.x(), v.y(), v.z()}; };
  report.add("method_jitter_sigma", triple(stats.noise.method_jitter));
  report.add("odometry_jitter_sigma", triple(stats.noise.odometry_jitter));
  report.add("odometry_translation_scale", stats.noise.translation_scale);
  report.add("odometry_rotation_scale", stats.noise.rotation_scale);
  report.add("streams", stats.noise.streams);
  report.add("method_slow_sigma", triple(stats.noise.method_slow));
  report.add("method_time_constant_scans",
             std::vector<double>{stats.noise.method_time_constant.x(), stats.noise.method_time_constant.y()});
  report.add("odometry_steps_refused", stats.steps_refused).add("poses_downweighted", stats.poses_downweighted);
  report.add("stretches", stats.stretches).add("max_change_m", stats.max_change_m);
  return report;
}

/// A warning when the guard did not trust at least 1 % of the increments, or any jump: then the
/// odometry was unreliable and those scans rest on scan matching alone; and one when the stamps
/// could not judge the odometry's speed (all equal, invented).
inline std::vector<std::string> odometry_warnings(const OdometryGuardStats& stats) {
  std::vector<std::string> warnings;
  if (stats.speedless > 0) {
    warnings.push_back(fmt::format(
        "odometry: {} of {} increments exceeded the speed bounds where the stamps carry no speed (not advancing, "
        "or the log's ordinary steps): there the speed bounds were off and the log's own step sizes judged jumps",
        stats.speedless, stats.checks));
  }
  const bool many = 100 * stats.untrusted() >= stats.checks && stats.untrusted() > 0;
  if (!many && stats.jumps == 0) return warnings;
  warnings.push_back(fmt::format("odometry: {} of {} increments not trusted ({} stalls over {} scans, {} catch-ups, {} jumps); "
                     "those scans were placed by scan matching alone",
                     stats.untrusted(), stats.checks, stats.stalls, stats.stalled_scans, stats.catch_ups, stats.jumps));
  return warnings;
}

}  // namespace slam2d::cli
