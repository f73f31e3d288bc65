// SPDX-License-Identifier: BSD-3-Clause
// Gaps in the scans (core/scan_gaps.hpp): which scan ends one, and how far the odometry drifted
// from the estimate over stretches as long as the gap; the overlay of two maps (core/occupancy_map).

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/scan_gaps.hpp"

namespace slam2d {
namespace {

// Scans 0.1 s apart: a pause of 10 s or more ends a gap. At a scan every 2 s, 20 intervals (40 s)
// are needed, and a 30 s pause ends none.
TEST(ScanGapDetector, CountsAPauseLongerThanTheSecondsAndTheTypicalIntervals) {
  ScanGapDetector fast;
  double t = 0.0;
  for (int i = 0; i < 50; ++i, t += 0.1) EXPECT_EQ(fast.gap_before(t), 0.0);
  EXPECT_NEAR(fast.gap_before(t + 12.0), 12.1, 1e-9);
  EXPECT_EQ(fast.gap_before(t + 12.1), 0.0);
  EXPECT_EQ(fast.gaps(), 1u);
  const auto after_slow_scans = [](double pause) {
    ScanGapDetector slow;
    double t = 0.0;
    for (int i = 0; i < 50; ++i, t += 2.0) slow.gap_before(t);
    return slow.gap_before(t - 2.0 + pause);
  };
  EXPECT_EQ(after_slow_scans(30.0), 0.0);
  EXPECT_EQ(after_slow_scans(41.0), 41.0);
  EXPECT_THROW(ScanGapDetector({.seconds = 0.0}), Error);
  EXPECT_THROW(ScanGapDetector({.periods = 0.5}), Error);
}

// An odometry whose heading drifts 0.01 rad per second against an estimate driving straight at
// 1 m/s: over 20 s it turns 0.2 rad away, and its end lies about 20 x 0.1 = 2 m aside. With only 10 s
// seen the drift over 20 s is twice that over 10 s; with less than 5 s (a quarter) it is unbounded.
TEST(OdometryDrift, IsTheLargestDisagreementOverStretchesAsLongAsTheGap) {
  std::vector<OdometryAndEstimate> history;
  SE2 odometry;
  for (int i = 0; i <= 600; ++i) {
    const double t = 0.1 * i;
    if (i > 0) odometry = odometry * SE2(0.1, 0.0, 0.001);
    history.push_back({t, odometry, SE2(t, 0.0, 0.0)});
  }
  const Drift drift = odometry_drift_over(history, 20.0);
  EXPECT_NEAR(drift.rotation, 0.2, 0.0015);  // the first pose at least 20 s on: 200 or 201 steps
  EXPECT_NEAR(drift.translation, 2.0, 0.05);
  const std::vector<OdometryAndEstimate> ten_seconds(history.begin(), history.begin() + 101);
  const Drift scaled = odometry_drift_over(ten_seconds, 20.0);
  EXPECT_NEAR(scaled.rotation, 2.0 * 0.1, 1e-9);  // 100 steps over the 10 s seen, twice
  const std::vector<OdometryAndEstimate> four_seconds(history.begin(), history.begin() + 41);
  EXPECT_TRUE(std::isinf(odometry_drift_over(four_seconds, 20.0).translation));
  EXPECT_TRUE(std::isinf(odometry_drift_over({}, 20.0).rotation));
}

// Two maps on one lattice, offset by (3, -2) cells: the overlay covers both, the upper map's known
// cells win, the lower one shows where the upper knows nothing.
TEST(OccupancyMapOverlay, KeepsTheUpperMapsKnownCellsOverTheLower) {
  OccupancyMap below;
  below.resolution = 0.1;
  below.origin = SE2(1.0, 2.0, 0.0);
  below.width = 4;
  below.height = 3;
  below.cells.assign(12, OccupancyMap::kFree);
  OccupancyMap above = below;
  above.origin = SE2(1.3, 1.8, 0.0);
  above.cells.assign(12, OccupancyMap::kUnknown);
  above.at(0, 2) = OccupancyMap::kOccupied;  // on below's cell (3, 0)
  above.at(3, 0) = 40;                       // outside below
  const OccupancyMap map = overlay(below, above);
  EXPECT_EQ(map.width, 7);
  EXPECT_EQ(map.height, 5);
  const auto at = [&](double x, double y) {
    const Eigen::Vector2i cell = map.cell_of({x, y});
    return map.at(cell.x(), cell.y());
  };
  EXPECT_EQ(at(1.35, 2.05), OccupancyMap::kOccupied);
  EXPECT_EQ(at(1.65, 1.85), 40);
  EXPECT_EQ(at(1.05, 2.25), OccupancyMap::kFree);   // below only
  EXPECT_EQ(at(1.05, 1.85), OccupancyMap::kUnknown);  // neither
  EXPECT_EQ(overlay(OccupancyMap{}, above), above);
  EXPECT_EQ(overlay(below, OccupancyMap{}), below);
}

}  // namespace
}  // namespace slam2d
