// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The known map a localizer runs in: the occupancy map, its likelihood field (grid/
// likelihood_field.hpp, Thrun et al. 2005 Table 6.3), the free cells (where a robot can stand:
// global localization and random-sample injection draw from them) and a nearest-sample table of
// the per-beam likelihood, the fast path of particle filters (one read per end point, no
// interpolation, no exp, no log).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/likelihood_field.hpp"
#include "slam2d/registration/likelihood_field_match.hpp"

namespace slam2d {

class LocalizationMap {
 public:
  /// Throws Error for an empty map, a map without free cells, or an invalid field configuration.
  explicit LocalizationMap(OccupancyMap map, const LikelihoodFieldConfig& field_config = {});

  const OccupancyMap& map() const { return map_; }
  const LikelihoodField& field() const { return field_; }
  /// Centres of the free cells (occupancy below 50 %, known), map frame.
  const std::vector<Eigen::Vector2d>& free_cells() const { return free_cells_; }
  /// True when the point lies in a known free cell.
  bool is_free(const Eigen::Vector2d& point_map) const;
  /// A pose uniform over the free cells (uniform within the cell) and over the heading.
  SE2 sample_free_pose(Rng& rng) const;

  /// log prod_i p(z_i | x): the likelihood field of Table 6.3 at the end points (robot frame)
  /// placed at T_map_robot, each read from the nearest sample (a density in 1/m) of a table of
  /// logs quantised to 0.001. 0 for no points.
  double scan_log_likelihood(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot) const;
  /// scan_log_likelihood at each pose, the same values, into `log_likelihoods`. Beam by beam over
  /// blocks of poses: a particle cloud's end points of one beam fall close together, so the
  /// table reads stay in the cache.
  void scan_log_likelihoods(const std::vector<Eigen::Vector2d>& points_robot, const std::vector<SE2>& poses,
                            std::vector<double>& log_likelihoods) const;
  /// The fraction of end points within `distance` (m) of an obstacle at T_map_robot (bilinear
  /// distance): how well a pose explains a scan, 1 for a perfect fit, whatever the spread. 0 for no points.
  double plausibility(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot, double distance) const;

  /// The scan's end points matched in the map from `guess` (likelihood-field least squares), or
  /// none for a poor fit: fewer than half of the end points within the matcher's inlier distance
  /// (a match that used up its iterations counts; the caller may ask for convergence). What follows
  /// a robot within an odometry stall (session.hpp) and what MCL's motion noise learns from.
  std::optional<MatchResult> match(const std::vector<Eigen::Vector2d>& points_robot, const SE2& guess,
                                   const LikelihoodFieldMatchConfig& config = {}) const;

  std::size_t memory_bytes() const;

 private:
  OccupancyMap map_;
  LikelihoodField field_;
  std::vector<Eigen::Vector2d> free_cells_;
  SE2 T_field_map_;               // the field's cell frame from the map frame
  double inverse_resolution_ = 0.0;
  // round(1000 log p) of the per-beam likelihood (1/m) at each field sample, stored in 8 x 8 tiles
  // (128 bytes, two cache lines) row by row: a particle cloud's end points around one beam's hit
  // touch a few tiles instead of one cache line per field row.
  std::vector<std::int16_t> log_density_;
  int tiles_x_ = 0;                         // tiles per row
  std::int16_t outside_log_density_ = 0;   // beyond the field: at max_distance

  struct FieldPose {  // a pose as the map from robot-frame metres to table samples
    float c, s, tx, ty;
  };
  FieldPose field_pose(const SE2& T_map_robot) const;
  std::uint32_t table_index(const FieldPose& pose, float px, float py) const;
};

}  // namespace slam2d
