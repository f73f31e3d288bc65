// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Gaps in the scans (the logger paused, the laser dropped out) and how far the odometry may have
// drifted across one. Across a gap only the odometry tells where the robot went; how much it can
// be trusted there is measured on the data before the gap, not assumed: the largest disagreement
// between the odometry's motion and the method's estimate over any stretch as long as the gap.
// Graph SLAM weighs its edge across the gap and bounds its loop closer's search with it, Hector
// bounds its search for its place in the map before the gap (docs/methods/graph_slam.md,
// docs/methods/hector.md, "Across a gap in the scans").

#include <cstddef>
#include <span>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

// A scan more than max(seconds, periods x the typical interval between scans) after the one before
// ends a gap. Where nothing was seen before the gap to measure the odometry's drift on, it is that
// of a path of `speed` x the gap's duration (graph SLAM also counts that distance as travelled).
// A gap across which the search window over the odometry's drift (three sigmas of it) stays within
// the tracker's reach from the odometry's prediction (track_*: Hector's pyramid's coarsest cells are 0.2 m, its rotation search
// 0.2 rad) is tracked through on the old map: the odometry is good enough there.
struct ScanGapConfig {
  double seconds = 10.0;
  double periods = 20.0;
  double speed = 1.0;
  double track_translation = 1.0;  // m
  double track_rotation = 0.3;     // rad
};

template <typename Fields>
void describe(Fields& f, ScanGapConfig& c) {
  f.number("seconds", c.seconds, "s", greater_than(0), "a scan at least this long after the one before ends a gap in the scans ...");
  f.number("periods", c.periods, "1", at_least(1), "... and at least this many typical scan intervals");
  f.number("speed", c.speed, "m/s", greater_than(0),
           "without a measured drift, the odometry's noise across a gap is that of a path this fast for the gap's duration");
  f.number("track_translation", c.track_translation, "m", at_least(0),
           "the tracker's reach: a gap across whose odometry drift the search window is at most this ...");
  f.number("track_rotation", c.track_rotation, "rad", at_least(0), "... and this is tracked through on the old map");
}

/// A search window over the odometry's drift across a gap (m, rad) within the tracker's reach.
bool within_tracker_reach(const ScanGapConfig& config, double window, double window_theta);

/// Throws Error for out-of-range values.
void validate(const ScanGapConfig& config);

/// Tells, scan by scan, whether a scan ends a gap. The typical interval is a running mean over the
/// intervals that end none.
class ScanGapDetector {
 public:
  explicit ScanGapDetector(const ScanGapConfig& config = {});
  /// The seconds since the scan before when the scan at `stamp` ends a gap, else 0.
  double gap_before(double stamp);
  std::size_t gaps() const { return gaps_; }

 private:
  ScanGapConfig config_;
  bool started_ = false;
  double last_stamp_ = 0.0;
  double typical_interval_ = 0.0;  // s; 0 until two scans were seen
  std::size_t gaps_ = 0;
};

/// A drift in translation and heading (standard deviations, or a largest disagreement).
struct Drift {
  double translation = 0.0;  // m
  double rotation = 0.0;     // rad
};


/// The odometry's pose and the method's estimate at one stamp.
struct OdometryAndEstimate {
  double stamp = 0.0;
  SE2 odometry;
  SE2 estimate;
};

/// Appends `pair` to `history` unless it comes less than half a second after the last one: poses
/// enough to measure the drift over a gap of ten seconds and more, a bounded number per second.
void add_to_history(std::vector<OdometryAndEstimate>& history, const OdometryAndEstimate& pair);

/// How far the odometry drifted from the estimate over stretches of `duration` seconds of
/// `history` (in stamp order, since the last gap): the largest disagreement of the two motions over
/// such a stretch, in translation and in heading, times duration / the stretch where less than
/// `duration` was seen. Unbounded (infinite) with fewer than two poses or with less than a quarter of
/// `duration` seen.
Drift odometry_drift_over(std::span<const OdometryAndEstimate> history, double duration);

}  // namespace slam2d
