#pragma once
// What the odometry guard (core/odometry_guard.hpp) found, as summary.json reports it for every
// method that reads wheel odometry.

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

}  // namespace slam2d::cli
