// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the odometry guard (core/odometry_guard.hpp) found, as summary.json reports it for every
// method that reads wheel odometry.

#include <fmt/core.h>

#include <optional>
#include <string>

#include "json.hpp"
#include "slam2d/core/odometry_guard.hpp"

namespace slam2d::cli {

inline JsonObject odometry_report(const OdometryGuardStats& stats) {
  JsonObject report;
  report.add("odometry_stalls", stats.stalls).add("odometry_stalled_scans", stats.stalled_scans);
  report.add("odometry_catch_ups", stats.catch_ups).add("odometry_jumps", stats.jumps);
  report.add("odometry_gaps", stats.gaps);
  return report;
}

/// A warning when the guard did not trust at least 1 % of the increments, or any jump: then the
/// odometry was unreliable and those scans rest on scan matching alone.
inline std::optional<std::string> odometry_warning(const OdometryGuardStats& stats) {
  const bool many = 100 * stats.untrusted() >= stats.checks && stats.untrusted() > 0;
  if (!many && stats.jumps == 0) return std::nullopt;
  return fmt::format("odometry: {} of {} increments not trusted ({} stalls over {} scans, {} catch-ups, {} jumps); "
                     "those scans were placed by scan matching alone",
                     stats.untrusted(), stats.checks, stats.stalls, stats.stalled_scans, stats.catch_ups, stats.jumps);
}

}  // namespace slam2d::cli
