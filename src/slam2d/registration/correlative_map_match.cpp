// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/correlative_map_match.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {

void validate(const MapMatchConfig& config) {
  check_fields(config, "MapMatchConfig");
  validate(config.correlative);
  validate(config.refinement);
}

namespace {

// Olson's covariance with a floor on each standard deviation: the lookup table is one cell wide
// and the refinement's own estimate (Censi's) ignores the map's errors.
Covariance3 floored(const Covariance3& covariance, const MapMatchConfig& config) {
  Covariance3 result = 0.5 * (covariance + covariance.transpose());
  const double floor_xy = config.min_sigma_translation * config.min_sigma_translation;
  const double floor_theta = config.min_sigma_rotation * config.min_sigma_rotation;
  result(0, 0) = std::max(result(0, 0), floor_xy);
  result(1, 1) = std::max(result(1, 1), floor_xy);
  result(2, 2) = std::max(result(2, 2), floor_theta);
  return make_positive_definite(result, 1e-3 * std::min(floor_xy, floor_theta));
}

// The scan's points within `distance` of a map point at the pose, and whether most of them see the
// map from behind. Both clouds' normals face their sensors (registration/normals.hpp): a point
// whose normal turns away from its map point's lies on the wall's far side, and a scan that fits
// walls from behind them fits either at a wrong place (an L of two walls matched onto a corner from
// beyond it) or where the map holds only one face of a thin wall (a room's inner walls onto the
// corridor's faces of the same walls): the caller weighs which (slam/graph/loop_closure.hpp). One
// point's normal is a fit of a few noisy neighbours: with 10 cm of range noise a right match's
// inliers turn away by more than 90 degrees in 30 % of the points and by more than 120 in 18 %. So
// a point turns away when its normal and its map point's are more than 120 degrees apart, and the
// match is seen from behind when more than half of the inliers whose point and map point carry
// normals do. Without normals (zero, or a cloud without them) nothing is judged.
constexpr double kTurnedAway = -0.5;  // cos 120 deg

struct Inliers {
  std::size_t count = 0;
  bool seen_from_behind = false;
};

Inliers count_inliers(const KdTree2& map, const PointCloud2& map_cloud, const PointCloud2& scan,
                      const SE2& T_map_robot, double distance) {
  const Eigen::Matrix2d R = T_map_robot.rotation();
  std::size_t inliers = 0, judged = 0, turned_away = 0;
  for (std::size_t n = 0; n < scan.size(); ++n) {
    const Neighbor nearest = map.nearest(T_map_robot * scan.points[n]);
    if (nearest.index >= map.size() || nearest.squared_distance > distance * distance) continue;
    ++inliers;
    if (!has_normal(scan, n) || !has_normal(map_cloud, nearest.index)) continue;
    ++judged;
    if ((R * scan.normals[n]).dot(map_cloud.normals[nearest.index]) < kTurnedAway) ++turned_away;
  }
  return {.count = inliers, .seen_from_behind = 2 * turned_away > judged};
}

}  // namespace

MatchMap make_match_map(PointCloud2 cloud, const MapMatchConfig& config) {
  MatchMap map;
  CorrelativeGridConfig grid_config = correlative_grid_config(config.correlative);
  grid_config.margin = std::max(config.correlative.window_x, config.correlative.window_y);  // the fast path
  if (!cloud.empty()) map.grid = CorrelativeGrid(cloud, grid_config);
  map.cloud = std::move(cloud);
  return map;
}

MatchResult match_correlative_map(const MatchMap& map, const PointCloud2& scan, const SE2& T_map_robot_guess,
                                  const MapMatchConfig& config) {
  MatchResult result;
  result.T_target_source = T_map_robot_guess;
  if (map.cloud.size() < 3 || scan.size() < 3) return result;
  const MatchResult coarse = match_correlative(map.grid, scan, T_map_robot_guess, config.correlative);
  result.iterations = coarse.iterations;
  result.score = static_cast<double>(coarse.inliers) / static_cast<double>(scan.size());
  if (!coarse.converged && result.score < config.min_score_at_window_edge) return result;
  result.converged = true;
  result.T_target_source = coarse.T_target_source;
  result.covariance = floored(coarse.covariance, config);
  result.degenerate = coarse.degenerate;
  result.weak_direction = coarse.weak_direction;
  result.information_eigenvalues = coarse.information_eigenvalues;
  if (config.refine) {
    const MatchResult fine =
        match_point_to_plane(map.grid.tree(), map.cloud, scan, coarse.T_target_source, config.refinement);
    const SE2 shift = coarse.T_target_source.between(fine.T_target_source);
    result.converged = fine.converged && shift.translation().norm() <= config.max_refinement_shift &&
                       std::abs(shift.theta()) <= config.correlative.window_theta;
    if (result.converged) {
      result.T_target_source = fine.T_target_source;
      result.residual = fine.residual;
    }
  }
  const Inliers inliers = count_inliers(map.grid.tree(), map.cloud, scan, result.T_target_source, config.inlier_distance);
  result.inliers = inliers.count;
  result.seen_from_behind = inliers.seen_from_behind;
  result.inlier_fraction = static_cast<double>(result.inliers) / static_cast<double>(scan.size());
  return result;
}

}  // namespace slam2d
