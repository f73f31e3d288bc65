// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Occupancy grid mapping in log-odds form: H. Moravec and A. Elfes, "High resolution maps from
// wide angle sonar", ICRA 1985; S. Thrun, W. Burgard, D. Fox, "Probabilistic Robotics", 2005,
// Table 9.1 (occupancy_grid_mapping, line 4: l += inverse_sensor_model - l_0, with l_0 = 0), with
// the two-valued inverse sensor model of ray-casting mappers: a hit on the end cell, a miss on the
// cells a beam passes through.
//
// Cells hold log-odds l = log(p / (1 - p)) in float, clamped to [logit(p_min), logit(p_max)],
// prior 0 (p = 0.5). Each cell also records the number of the last scan that updated it: 0 means
// never observed ("unknown"), which is how is_known() tells an observed p = 0.5 from an unknown
// cell, and how a scan updates each cell at most once.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/grid_geometry.hpp"
#include "slam2d/grid/tiled_grid.hpp"

namespace slam2d {

struct OccupancyGridConfig {
  double resolution = 0.05;
  double probability_hit = 0.7;
  double probability_miss = 0.4;
  double probability_min = 0.12;
  double probability_max = 0.97;
  // A no-return reading may be a dropout on a near wall, so it clears only a short way
  // (Cartographer's missing_data_ray_length is 5 m too).
  double max_clear_range = 5.0;
  double max_range = 100.0;
  // Neighbouring returns on one surface mark the cells between them too, with this share of a
  // hit's log-odds (OccupancyGrid::integrate_scan); 0, the textbook model, turns it off. The RBPF's
  // maps have it at 0.5; Hector's an option (docs/methods/rbpf.md, "A grazing wall as a wall").
  double surface_hit_weight = 0.0;
};

template <typename Fields>
void describe(Fields& f, OccupancyGridConfig& c) {
  f.number("resolution", c.resolution, "m per cell", greater_than(0), "cell size");
  f.number("probability_hit", c.probability_hit, "1", open_interval(0.5, 1), "inverse sensor model: P(occupied | hit)");
  f.number("probability_miss", c.probability_miss, "1", open_interval(0, 0.5), "P(occupied | ray passed through)");
  f.number("probability_min", c.probability_min, "1", open_interval(0, 0.5), "clamp; keeps cells able to change");
  f.number("probability_max", c.probability_max, "1", open_interval(0.5, 1), "clamp; keeps cells able to change");
  f.number("max_clear_range", c.max_clear_range, "m", at_least(0),
           "no-return beams clear free space up to here and never mark");
  f.number("max_range", c.max_range, "m", greater_than(0), "returns at or beyond are treated as no-return beams");
  f.number("surface_hit_weight", c.surface_hit_weight, "1", between(0, 1),
           "share of a hit for the cells between neighbouring returns in a line with two more (a grazing wall, not dots a beam apart); 0: off");
}

struct OccupancyCell {
  float log_odds = 0.0f;        // log(p / (1 - p)), clamped
  std::uint32_t last_scan = 0;  // 0: never observed; else the number of the last scan that updated it
};

class OccupancyGrid {
 public:
  /// Throws Error for a configuration outside the ranges documented on OccupancyGridConfig.
  explicit OccupancyGrid(OccupancyGridConfig config = {});

  /// Ray casting (Bresenham, integer) from the sensor's cell: a miss update on every cell up to,
  /// not including, the end cell, a hit update on the end cell. Readings >= range_max (or
  /// >= config.max_range) are no-return beams: they clear free space up to
  /// min(reading, max_clear_range) and mark nothing. NaN, inf, non-positive and below-range_min
  /// readings are ignored. Each cell is updated at most once per scan; a cell both hit and passed
  /// through gets the hit. The grid origin is the map frame's origin. Throws Error for a
  /// non-finite pose or scan geometry, or a pose beyond GridGeometry::kMaxCellIndex cells.
  /// The cells between two neighbouring returns on one surface (four returns or more in a line)
  /// get config.surface_hit_weight of a hit's log-odds, once per scan, a cell hit or passed
  /// through keeping that (surface_steps).
  void integrate_scan(const LaserScan& scan, const SE2& T_map_robot);

  /// A step between neighbouring returns on one surface, in the map frame.
  struct SurfaceStep {
    Eigen::Vector2d from;
    Eigen::Vector2d to;
  };
  /// The scan's surface steps at the sensor pose T_map_sensor: the same at any resolution, so a
  /// map pyramid finds them once for its levels (steps within one cell of this grid's resolution
  /// along both axes are left out: no level has a cell between their ends).
  std::vector<SurfaceStep> surface_steps(const LaserScan& scan, const SE2& T_map_sensor);
  /// integrate_scan with the scan's surface steps already found (by any grid with this one's
  /// max_range and a resolution no coarser; ignored where surface_hit_weight is 0).
  void integrate_scan(const LaserScan& scan, const SE2& T_map_robot, const std::vector<SurfaceStep>& steps);

  /// P(occupied) of the cell holding a map-frame point; 0.5 for unknown cells (and for points
  /// that are not finite or lie beyond GridGeometry::kMaxCellIndex cells).
  double probability(const Eigen::Vector2d& point) const {
    return geometry_.in_index_range(point) ? probability(geometry_.cell_of(point)) : 0.5;
  }
  double probability(CellIndex cell) const;
  /// Log-odds of a cell; 0 for unknown cells.
  double log_odds(CellIndex cell) const { return cells_.at(cell).log_odds; }
  bool is_known(CellIndex cell) const { return cells_.at(cell).last_scan != 0; }

  /// The finished map, cropped to the observed cells plus a one-cell margin (unknown) on each
  /// side: observed cells hold round(100 p), unobserved ones -1. Empty (0 x 0) before any update.
  OccupancyMap to_occupancy_map() const;

  /// Bounding box of the observed cells (empty before any update).
  const CellBox& observed_box() const { return cells_.bounding_box(); }
  const GridGeometry& geometry() const { return geometry_; }
  const TiledGrid<OccupancyCell>& cells() const { return cells_; }
  /// Number of scans integrated so far.
  std::uint32_t scan_count() const { return scan_count_; }
  std::size_t memory_bytes() const;
  const OccupancyGridConfig& config() const { return config_; }

 private:
  struct Ray {
    CellIndex end;
    bool hit;  // false for a no-return beam
  };
  std::vector<Ray> cast_rays(const LaserScan& scan, const SE2& T_map_sensor, CellIndex start, CellBox& box);
  std::vector<CellIndex> surface_cells(const std::vector<SurfaceStep>& steps) const;
  const std::vector<Eigen::Vector2d>& beam_directions(const LaserScan& scan);
  void apply_hits(const std::vector<Ray>& rays, const std::vector<CellIndex>& surface);
  void apply_misses(const std::vector<Ray>& rays, CellIndex start);

  OccupancyGridConfig config_;
  GridGeometry geometry_;
  float log_odds_hit_;
  float log_odds_surface_;
  float log_odds_miss_;
  float log_odds_min_;
  float log_odds_max_;
  std::uint32_t scan_count_ = 0;
  TiledGrid<OccupancyCell> cells_;
  // (cos, sin) of every beam's bearing for the last scan geometry (angle_min, angle_increment, size).
  std::vector<Eigen::Vector2d> beam_directions_;
  double directions_angle_min_ = 0.0;
  double directions_angle_increment_ = 0.0;
};

/// log(p / (1 - p)).
double logit(double probability);
/// The inverse of logit: 1 / (1 + exp(-log_odds)).
double probability_from_log_odds(double log_odds);

}  // namespace slam2d
