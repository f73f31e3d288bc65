// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scan-to-map matching against a point map (graph SLAM's loop closures, the "scan matcher" of
// Karto): the scan's end points (robot frame) against a cloud of map-frame points (graph SLAM:
// earlier keyframes' points, slam/graph/keyframes.hpp map_cloud), rasterised
// into a correlative lookup table (E. Olson, "Real-time correlative scan matching", ICRA 2009) and
// searched by branch-and-bound over a window around the guess; the best pose is then refined by
// point-to-line least squares against the same points (K.-L. Low 2004, registration/
// point_to_plane.hpp). The covariance is Olson's, from the response over the window (Eq. (3)),
// floored so that no constraint claims more than the sensor can give.
//
// The MatchResult: T_target_source is T_map_robot (the guess when the search found nothing);
// covariance Olson's, floored (unknown when the search found nothing); converged: the search found
// an inner maximum above min_score (or one on the window's edge with min_score_at_window_edge) and,
// with refine, the refinement converged within max_refinement_shift (when only the refinement
// fails: converged = false with the search's pose and covariance); score: the search's share of
// the scan on the table's occupied cells; inliers / inlier_fraction: scan points within
// inlier_distance of a map point at the estimate; seen_from_behind: the scan sees the map from
// behind (where both clouds carry normals, which face their sensors: more than half of the inliers'
// normals turn more than 120 degrees away from their map points'; an L of walls fitted onto a
// corner from beyond it, or a thin wall's other face where the map holds only one); degenerate /
// weak_direction: the search's.
//
// Loop closure matches a keyframe against a chain of old keyframes over a large window
// (slam/graph/loop_closure.hpp).

#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/correlative.hpp"
#include "slam2d/registration/match_result.hpp"
#include "slam2d/registration/point_to_plane.hpp"

namespace slam2d {

struct MapMatchConfig {
  // Coarse is enough: the refinement does the fine work, the search only has to land in its basin.
  CorrelativeConfig correlative{.resolution = 0.05, .sigma = 0.05, .window_x = 0.2, .window_y = 0.2,
                                .window_theta = 0.2, .angular_step = 0.004, .min_score = 0.3};
  bool refine = true;
  PointToPlaneConfig refinement{.max_correspondence_distance = 0.15};
  double max_refinement_shift = 0.1;
  double min_sigma_translation = 0.005;
  double min_sigma_rotation = 0.002;
  double inlier_distance = 0.1;
  double map_voxel = 0.02;
  // A best pose on the window's edge (a corridor's axis, where the response is flat) is kept when
  // this fraction of the scan lies on the map; its covariance then shows the flat direction.
  double min_score_at_window_edge = 0.8;
};

template <typename Fields>
void describe(Fields& f, MapMatchConfig& c) {
  f.section("correlative", c.correlative, "the search (coarse is enough: the refinement does the fine work)");
  f.flag("refine", c.refine, "point-to-line refinement of the correlative pose");
  f.section("refinement", c.refinement, "the refinement's point-to-line ICP");
  f.number("max_refinement_shift", c.max_refinement_shift, "m", at_least(0), "a refinement farther from the correlative pose is discarded");
  f.number("min_sigma_translation", c.min_sigma_translation, "m", greater_than(0), "floor of the constraint's standard deviations");
  f.number("min_sigma_rotation", c.min_sigma_rotation, "rad", greater_than(0), "");
  f.number("inlier_distance", c.inlier_distance, "m", greater_than(0), "a scan point this near a map point counts in inlier_fraction");
  f.number("map_voxel", c.map_voxel, "m", at_least(0), "map points are thinned to one per voxel (0: all)");
  f.number("min_score_at_window_edge", c.min_score_at_window_edge, "1", between(0, 1),
           "a best pose on the window's edge (a corridor's axis) is kept when this fraction of the scan lies on the map; 1 never keeps one");
}

/// Throws Error for out-of-range values.
void validate(const MapMatchConfig& config);

/// A place searched for over a window of metres and radians (graph SLAM's global loop search,
/// Hector's search after a gap), coarse then fine. The coarse search: a 10 cm table under a 10 cm
/// kernel, 0.57 deg steps (a point 10 m out moves one cell per step), no refinement; its window is
/// set per search.
inline MapMatchConfig wide_search_coarse() {
  return {.correlative = {.resolution = 0.1, .sigma = 0.1, .angular_step = 0.01, .min_score = 0.5},
          .refine = false,
          .map_voxel = 0.05,
          .min_score_at_window_edge = 1.0};
}

/// The fine search around the coarse pose, with the refinement.
inline MapMatchConfig wide_search_fine() {
  return {.correlative = {.resolution = 0.05, .sigma = 0.05, .window_x = 0.3, .window_y = 0.3, .window_theta = 0.03,
                          .angular_step = 0.004, .min_score = 0.5},
          .refinement = {.max_correspondence_distance = 0.3},
          .max_refinement_shift = 0.3,
          .min_sigma_translation = 0.01,
          .min_sigma_rotation = 0.004,
          .min_score_at_window_edge = 1.0};
}

/// The map side of a match, built once and matched against many scans: the map-frame points
/// (with normals) and their correlative lookup table.
struct MatchMap {
  PointCloud2 cloud;
  CorrelativeGrid grid;
};

/// Rasterises the cloud with the config's table parameters (an empty cloud gives an empty map).
MatchMap make_match_map(PointCloud2 cloud, const MapMatchConfig& config);

/// Matches the robot-frame `scan` against the map from the guess. A map or scan of fewer than 3
/// points gives converged = false and the guess.
MatchResult match_correlative_map(const MatchMap& map, const PointCloud2& scan, const SE2& T_map_robot_guess,
                                  const MapMatchConfig& config);

}  // namespace slam2d
