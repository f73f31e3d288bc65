// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// After a gap in the scans (core/scan_gaps.hpp), the search of the map before it for the scans after
// it (not in the papers of Hector or GMapping). A method with one map and no loop closer matches
// the first scan after the gap against its map from the odometry's prediction; after tens of
// metres of driving unseen the prediction is metres off, and the scan snaps onto whatever place of
// the map is nearest (Intel with 198 s of scans missing: Hector 18.7 m and the RBPF 20.2 m on the
// relations across the gap, the odometry alone 13.9 m). So the method maps on in a new map from the
// prediction, and this class searches the old one:
// - the window is `sigmas` x the odometry's drift over the gap, measured before it (core/scan_gaps's
//   odometry_drift_over; without odometry or history, the whole map and every heading), widened by
//   drift_per_metre of the path since the gap (the new map's own drift);
// - each scan (every attempt_distance travelled, later every attempt_spacing of the path since the
//   gap) is matched against the old map's occupied cells, coarse then fine, over the window;
// - a match must pass min_score and min_inlier_fraction, and the old map must not contradict the
//   new one moved there (registration/free_space_check.hpp: an alias a few doors along a corridor
//   fits the scan, not the walls beyond it);
// - a match within the tracker's reach of the pose in the new map, or two matches of scans
//   confirm_min_distance to confirm_max_distance apart that put the new map at the same place,
//   place the new map in the old one; after max_attempts the method goes on in the new map alone.
// Hector (docs/methods/hector.md) and the RBPF (docs/methods/rbpf.md) use it, "Across a gap in the
// scans"; graph SLAM's loop closer does its own search (docs/methods/graph_slam.md).

#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/scan_gaps.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/registration/correlative_map_match.hpp"

namespace slam2d {

struct GapRelocalizationConfig {
  bool enabled = true;
  ScanGapConfig gap{};
  double sigmas = 3.0;
  double min_window = 0.5;         // m
  double max_window = 100.0;       // m; and never wider than the map
  double min_window_theta = 0.1;   // rad
  // The coarse search and the fine one around its pose (graph SLAM's global search's settings:
  // registration/correlative_map_match.hpp's wide search).
  MapMatchConfig coarse = wide_search_coarse();
  MapMatchConfig fine = wide_search_fine();
  double min_score = 0.6;
  double min_inlier_fraction = 0.8;
  double confirm_min_distance = 0.5;   // m travelled between the two scans ...
  double confirm_max_distance = 5.0;   // ... at most
  double confirm_tolerance = 0.25;     // m
  double confirm_rotation_tolerance = 0.05;  // rad
  double verify_distance = 0.2;        // m: a new map's wall this near an old one agrees ...
  double max_contradiction = 0.15;     // ... and at most this share of them may land on free space
  double attempt_distance = 0.2;       // m travelled between two attempts ...
  double attempt_spacing = 0.25;       // ... at least this share of the path since the gap
  double drift_per_metre = 0.02;       // m and rad the window widens per metre since the gap
  int max_attempts = 100;
  int max_mapped_scans = 2000;         // the new map's scans kept to go into the old one
};

template <typename Fields>
void describe(Fields& f, GapRelocalizationConfig& c) {
  f.flag("enabled", c.enabled, "after a gap in the scans, search the map before it");
  f.section("gap", c.gap, "what is a gap in the scans");
  f.number("sigmas", c.sigmas, "1", greater_than(0), "the search window: this many times the odometry's drift over the gap ...");
  f.number("min_window", c.min_window, "m", greater_than(0), "... at least this ...");
  f.number("max_window", c.max_window, "m", greater_than(0), "... and at most this or the map's diagonal (also without a measured drift)");
  f.number("min_window_theta", c.min_window_theta, "rad", greater_than(0), "the heading window at least this (at most pi)");
  f.section("coarse", c.coarse, "the coarse search over the window");
  f.section("fine", c.fine, "the fine search and refinement around the coarse pose");
  f.number("min_score", c.min_score, "1", between(0, 1), "correlative response a match needs");
  f.number("min_inlier_fraction", c.min_inlier_fraction, "1", between(0, 1), "after refinement, a match needs this");
  f.number("confirm_min_distance", c.confirm_min_distance, "m", at_least(0),
           "two agreeing matches of scans at least this far apart along the path relocalize ...");
  f.number("confirm_max_distance", c.confirm_max_distance, "m", at_least(0), "... and at most this");
  f.number("confirm_tolerance", c.confirm_tolerance, "m", greater_than(0), "two matches agree within this ...");
  f.number("confirm_rotation_tolerance", c.confirm_rotation_tolerance, "rad", greater_than(0), "... and this");
  f.number("verify_distance", c.verify_distance, "m", greater_than(0),
           "a match is checked against the whole new map: its occupied cells this near an old one agree ...");
  f.number("max_contradiction", c.max_contradiction, "1", between(0, 1),
           "... and at most this share of those the old map saw may land on its free cells");
  f.number("attempt_distance", c.attempt_distance, "m", at_least(0), "travelled between two attempts ...");
  f.number("attempt_spacing", c.attempt_spacing, "1", at_least(0), "... and at least this share of the path since the gap");
  f.number("drift_per_metre", c.drift_per_metre, "m (rad) per m", at_least(0),
           "the window widens by this per metre travelled since the gap (the new map's drift)");
  f.number("max_attempts", c.max_attempts, "1", at_least(1), "attempts per gap before the method goes on in the new map alone ...");
  f.number("max_mapped_scans", c.max_mapped_scans, "1", at_least(1), "... or scans in the new map (kept until then)");
}

/// Throws Error for settings outside the documented ranges.
void validate(const GapRelocalizationConfig& config);

/// Gaps in the scans and the searches after them, per method run.
struct GapStats {
  std::size_t gaps = 0;
  std::size_t tracked = 0;      // gaps whose odometry was good enough to track through on the old map
  std::size_t attempts = 0;     // scans searched for in the map before a gap
  std::size_t relocalized = 0;  // gaps after which the method found its place in the map before it
  std::size_t abandoned = 0;    // ... and after which it went on in a new map (max_attempts, the next gap)
};

/// The map before one gap, searched for the scans after it. The new map starts at the odometry's
/// prediction in the old map's frame, so a scan's pose in the new map is where the search centres.
class SearchBeforeGap {
 public:
  /// `before`: the old map's finest level; `drift`: the odometry's over the gap (infinite: unknown).
  SearchBeforeGap(const GapRelocalizationConfig& config, const OccupancyGrid& before, const Drift& drift);

  /// The search's outcome after one more scan.
  struct Verdict {
    std::optional<SE2> T_before_new;  // the new map's pose in the old one, once found
    bool give_up = false;             // max_attempts spent
  };
  /// One scan after the gap: its usable end points (robot frame, levelled) at its pose in the new
  /// map. `new_walls` gives the new map's occupied points (its frame); it is called only to check
  /// a match.
  Verdict add(const std::vector<Eigen::Vector2d>& points, const SE2& T_new_robot,
              const std::function<PointCloud2()>& new_walls);

  const OccupancyGrid& before() const { return before_; }
  int attempts() const { return attempts_; }
  double window() const { return window_; }
  double window_theta() const { return window_theta_; }

 private:
  std::optional<SE2> search(const std::vector<Eigen::Vector2d>& points, const SE2& T_new_robot) const;
  bool contradicted(const SE2& T_before_new, PointCloud2 new_walls) const;

  GapRelocalizationConfig config_;
  OccupancyGrid before_;
  MatchMap coarse_{};      // its occupied cells, for the coarse and the fine search
  MatchMap fine_{};
  double window_ = 0.0;        // m
  double window_theta_ = 0.0;  // rad
  std::optional<SE2> last_pose_;                      // the previous scan's pose in the new map
  std::vector<std::pair<SE2, double>> candidates_{};  // T_before_new of each good match, at the path's length
  double path_ = 0.0;          // m travelled since the gap
  double attempted_at_ = 0.0;  // path at the last attempt
  int attempts_ = 0;
};

}  // namespace slam2d
