// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/relocalization/search_before_gap.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/error.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/registration/free_space_check.hpp"

namespace slam2d {

namespace {

// The coarse search over the window.
MapMatchConfig coarse_search(const GapRelocalizationConfig& config, double window, double window_theta) {
  MapMatchConfig coarse = config.coarse;
  coarse.correlative.window_x = coarse.correlative.window_y = window;
  coarse.correlative.window_theta = window_theta;
  return coarse;
}

}  // namespace

void validate(const GapRelocalizationConfig& config) {
  check_fields(config, "GapRelocalizationConfig");
  check(config.max_window >= config.min_window, "GapRelocalizationConfig: max_window must be >= min_window");
  validate(config.gap);
  validate(config.coarse);
  validate(config.fine);
}

SearchBeforeGap::SearchBeforeGap(const GapRelocalizationConfig& config, const OccupancyGrid& before, const Drift& drift)
    : config_(config), before_(before) {
  // No window wider than the map: an unbounded drift (no odometry, too little seen) searches it all.
  const OccupancyMap map = before_.to_occupancy_map();
  const double widest = std::min(config_.max_window, std::hypot(map.width, map.height) * map.resolution);
  window_ = std::clamp(config_.sigmas * drift.translation, std::min(config_.min_window, widest), widest);
  window_theta_ = std::clamp(config_.sigmas * drift.rotation, config_.min_window_theta, std::numbers::pi);
  const PointCloud2 occupied = wall_points(before_);
  coarse_ = make_match_map(occupied, coarse_search(config_, window_, window_theta_));  // the table's levels fit the window
  fine_ = make_match_map(occupied, config_.fine);
}

// One attempt every attempt_distance travelled (while a candidate waits), else every share of the
// path since the gap: a match that agrees with an earlier one of a scan at least
// confirm_min_distance away, or one within the tracker's reach, places the new map.
SearchBeforeGap::Verdict SearchBeforeGap::add(const std::vector<Eigen::Vector2d>& points, const SE2& T_new_robot,
                                              const std::function<PointCloud2()>& new_walls) {
  const GapRelocalizationConfig& c = config_;
  if (last_pose_) path_ += (T_new_robot.translation() - last_pose_->translation()).norm();
  last_pose_ = T_new_robot;
  // Candidates too far back along the path to be confirmed go.
  std::erase_if(candidates_, [&](const auto& candidate) { return path_ - candidate.second > c.confirm_max_distance; });
  const double spacing = candidates_.empty() ? std::max(c.attempt_distance, c.attempt_spacing * path_) : c.attempt_distance;
  if (attempts_ > 0 && path_ - attempted_at_ < spacing) return {};
  attempted_at_ = path_;
  ++attempts_;
  Verdict verdict;
  const std::optional<SE2> found = search(points, T_new_robot);
  const std::optional<SE2> T_before_new = found ? std::optional<SE2>(*found * T_new_robot.inverse()) : std::nullopt;
  if (T_before_new && !contradicted(*T_before_new, new_walls())) {
    const SE2 correction = T_new_robot.between(*found);
    if (within_tracker_reach(c.gap, correction.translation().norm(), std::abs(correction.theta()))) {
      verdict.T_before_new = T_before_new;  // where the tracker's own match would have put it: no alias to fear
      return verdict;
    }
    for (const auto& [earlier, at] : candidates_) {
      const SE2 apart = (earlier * T_new_robot).between(*found);
      if (path_ - at >= c.confirm_min_distance && apart.translation().norm() <= c.confirm_tolerance &&
          std::abs(apart.theta()) <= c.confirm_rotation_tolerance) {
        verdict.T_before_new = T_before_new;
        return verdict;
      }
    }
    candidates_.emplace_back(*T_before_new, path_);
  }
  verdict.give_up = attempts_ >= c.max_attempts;
  return verdict;
}

// The scan's pose in the map before the gap, searched for around its pose in the new map over the
// window, coarse then fine; none unless the fine match passes the thresholds.
std::optional<SE2> SearchBeforeGap::search(const std::vector<Eigen::Vector2d>& points, const SE2& T_new_robot) const {
  const GapRelocalizationConfig& c = config_;
  PointCloud2 scan;
  scan.points = points;
  // The new map's own drift since the gap widens the window.
  const double window = window_ + c.drift_per_metre * path_;
  const double window_theta = std::min(window_theta_ + c.drift_per_metre * path_, std::numbers::pi);
  const MatchResult found = match_correlative_map(coarse_, scan, T_new_robot, coarse_search(c, window, window_theta));
  if (!found.converged) return std::nullopt;
  const MatchResult fine = match_correlative_map(fine_, scan, found.T_target_source, c.fine);
  if (!fine.converged || fine.degenerate || fine.score < c.min_score || fine.inlier_fraction < c.min_inlier_fraction) {
    return std::nullopt;
  }
  return fine.T_target_source;
}

// Whether the map before the gap contradicts the new map moved by T_before_new: more than
// max_contradiction of the new map's occupied cells that land where the old map saw anything land
// on cells it saw free (none of its occupied cells within verify_distance). A corridor matched a
// few doors along, a room matched in its twin: the scan fits, the walls beyond it do not.
bool SearchBeforeGap::contradicted(const SE2& T_before_new, PointCloud2 new_walls) const {
  for (Point2& point : new_walls.points) point = T_before_new * point;
  return check_free_space(before_, fine_.grid.tree(), new_walls.points, config_.verify_distance)
      .contradicted(config_.max_contradiction);
}

}  // namespace slam2d
