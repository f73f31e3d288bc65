// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Graph SLAM configurations the tests compare the defaults against (header only: the binaries that
// include it link slam2d::slam themselves).

#include "slam2d/slam/graph/graph_slam.hpp"

namespace slam2d::test {

/// Graph SLAM's defaults before 2026-12-03: the tracker's prior of constant weight (sigma 0.1 m,
/// 0.058 rad, a plain Gaussian, no retry after a poor fit), the fixed sequential covariance and an
/// odometry edge beside each sequential edge (docs/fusion_by_uncertainty.md).
inline GraphSlamConfig graph_with_fixed_tracker_prior() {
  GraphSlamConfig config;
  config.tracking.prior_from_motion_noise = false;
  config.tracking.prior_kernel = {};
  config.tracking.recovery_residual = 1.0;
  config.sequential_from_match = false;
  config.odometry_edges = true;
  return config;
}

/// Graph SLAM's defaults without the tracker's correction of the odometry's systematic error (the
/// defaults before 2026-12-07). The tests whose odometry errs on purpose (a heading bias that makes
/// a drift, a fault or a gap that trips a mechanism) compare that mechanism with and without on
/// these: the calibration takes a simulated bias out, and on the real logs it changes which runs
/// a fault trips, so it would decide the comparison instead of the mechanism.
inline GraphSlamConfig graph_without_calibration(GraphSlamConfig config = {}) {
  config.tracking.odometry_calibration.window = 0.0;
  return config;
}

}  // namespace slam2d::test
