// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Keyframes of graph SLAM: the scans that become graph nodes. A scan is taken when the robot
// moved a minimum distance or turned a minimum angle since the last keyframe (Karto's minimum
// travel distance and heading), or when a minimum time passed (the time-based subset of the 2015
// indoor-localization study), so that a standing robot still contributes its best, undistorted
// scans.

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct KeyframeConfig {
  double min_distance = 0.2;
  double min_angle = 0.2;
  double min_time = 10.0;
  // Lifelong mapping: a keyframe within redundant_radius and redundant_angle of an older keyframe
  // that keeps its points, once the graph links the two (a loop edge near both), drops its points
  // and scan and stays a node only. A radius of 0 keeps every keyframe's data (Karto). The default
  // was chosen by leave-one-out on Intel, ACES and FR079 (docs/defaults.md).
  double redundant_radius = 0.25;
  double redundant_angle = 0.25;
  // A released keyframe's node merges into its witness's: its edges move there (GraphSlam::
  // apply_merges), so the graph, like the data, grows with the place and not with the time. Off by
  // default: its poses are then held at the witness's, and later passes lose accuracy
  // (docs/methods/graph_slam.md, "Merged nodes").
  bool merge_released = false;
};

template <typename Fields>
void describe(Fields& f, KeyframeConfig& c) {
  f.number("min_distance", c.min_distance, "m", at_least(0), "a new keyframe once the robot moved this far ...");
  f.number("min_angle", c.min_angle, "rad", at_least(0), "... or turned this much ...");
  f.number("min_time", c.min_time, "s", at_least(0), "... or this long passed; 0 disables the time rule");
  f.number("redundant_radius", c.redundant_radius, "m", at_least(0),
           "lifelong: a keyframe this near an older one that keeps its points, and linked to it, drops its own; 0: off");
  f.number("redundant_angle", c.redundant_angle, "rad", at_least(0), "... and turned at most this much from it");
  f.flag("merge_released", c.merge_released,
         "lifelong: a released keyframe's node merges into its witness's (its edges move there); false: it stays a node");
}

/// A graph node's scan: its end points in the robot frame, with normals (from the scan order).
struct Keyframe {
  std::size_t node = 0;        // index into the pose graph
  std::size_t scan = 0;        // index of the scan among all scans added
  double stamp = 0.0;          // s
  PointCloud2 cloud;           // robot frame
  double path_distance = 0.0;  // m travelled from the first keyframe (estimate at creation)
  // The first keyframe after a gap in the scans: the edges from the keyframe before hold only the
  // odometry over the gap, so the drift across them is the odometry's over that time (standard
  // deviations; infinite where nothing tells it), not the loop closer's model of the tracker's.
  bool after_gap = false;
  double gap_drift_translation = 0.0;  // m
  double gap_drift_rotation = 0.0;     // rad
  // Lifelong (keyframes.redundant_radius > 0):
  bool released = false;                  // its points were dropped (a node only, no loop target)
  bool witness = false;                   // it witnessed a release: it keeps its data for good
  std::vector<std::size_t> loop_anchors;  // the keyframes its loop edges start at
};

/// Throws Error for negative or non-finite values.
void validate(const KeyframeConfig& config);

class KeyframeSelector {
 public:
  explicit KeyframeSelector(const KeyframeConfig& config = {});
  /// True when a scan at `T_map_robot` and `stamp` should become a keyframe (always for the first).
  bool is_keyframe(const SE2& T_map_robot, double stamp) const;
  void accept(const SE2& T_map_robot, double stamp);

 private:
  KeyframeConfig config_;
  std::optional<SE2> last_pose_;
  double last_stamp_ = 0.0;
};

/// Map-frame points (and normals) of the keyframes, each at its pose, within `radius` of `center`,
/// one per `voxel` x `voxel` cell (the first keyframe's first: the same wall seen from many
/// keyframes is rasterised once). voxel = 0 keeps every point.
PointCloud2 map_cloud(const std::vector<const Keyframe*>& keyframes, const std::vector<SE2>& T_map_keyframe,
                      const Eigen::Vector2d& center, double radius, double voxel);

}  // namespace slam2d
