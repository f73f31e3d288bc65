// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/occupancy_grid.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/grid/ray_casting.hpp"

namespace slam2d {

namespace {

using CellGrid = TiledGrid<OccupancyCell>;

void validate(const OccupancyGridConfig& config) { check_fields(config, "OccupancyGridConfig"); }

/// Writes into one tile after another, remembering the last tile: neighbouring cells of a ray
/// mostly share it, which saves the table lookup and the copy-on-write check.
class TileCursor {
 public:
  explicit TileCursor(CellGrid& grid) : grid_(grid) {}
  OccupancyCell& operator()(CellIndex cell) {
    const CellIndex tile = CellGrid::tile_of(cell);
    if (tile != tile_) {
      cells_ = grid_.mutable_tile(tile);
      tile_ = tile;
    }
    return cells_[CellGrid::offset_in_tile(cell)];
  }

 private:
  CellGrid& grid_;
  CellIndex tile_{INT_MIN, INT_MIN};
  OccupancyCell* cells_ = nullptr;
};

}  // namespace

double logit(double probability) { return std::log(probability / (1.0 - probability)); }

double probability_from_log_odds(double log_odds) { return 1.0 / (1.0 + std::exp(-log_odds)); }

OccupancyGrid::OccupancyGrid(OccupancyGridConfig config) : config_(config) {
  validate(config_);
  geometry_.resolution = config_.resolution;
  log_odds_hit_ = static_cast<float>(logit(config_.probability_hit));
  log_odds_surface_ = static_cast<float>(config_.surface_hit_weight * logit(config_.probability_hit));
  log_odds_miss_ = static_cast<float>(logit(config_.probability_miss));
  log_odds_min_ = static_cast<float>(logit(config_.probability_min));
  log_odds_max_ = static_cast<float>(logit(config_.probability_max));
}

double OccupancyGrid::probability(CellIndex cell) const {
  const OccupancyCell& c = cells_.at(cell);
  return c.last_scan == 0 ? 0.5 : probability_from_log_odds(c.log_odds);
}

void OccupancyGrid::integrate_scan(const LaserScan& scan, const SE2& T_map_robot) {
  const bool surfaces = config_.surface_hit_weight > 0.0 && T_map_robot.vector().allFinite();
  integrate_scan(scan, T_map_robot,
                 surfaces ? surface_steps(scan, T_map_robot * scan.T_robot_sensor) : std::vector<SurfaceStep>{});
}

void OccupancyGrid::integrate_scan(const LaserScan& scan, const SE2& T_map_robot, const std::vector<SurfaceStep>& steps) {
  check(T_map_robot.vector().allFinite(), "OccupancyGrid::integrate_scan: non-finite robot pose");
  check(std::isfinite(scan.angle_min) && std::isfinite(scan.angle_increment),
        "OccupancyGrid::integrate_scan: non-finite scan angles");
  const SE2 T_map_sensor = T_map_robot * scan.T_robot_sensor;
  // Every end point lies within max(max_range, max_clear_range) of the sensor.
  const double reach = std::max(config_.max_range, config_.max_clear_range) / config_.resolution;
  check(T_map_sensor.vector().allFinite() &&
            geometry_.in_index_range(T_map_sensor.translation(), GridGeometry::kMaxCellIndex - reach - 2.0),
        "OccupancyGrid::integrate_scan: sensor pose non-finite or too far from the map origin");
  const CellIndex start = geometry_.cell_of(T_map_sensor.translation());
  CellBox box;
  box.extend(start);
  const std::vector<Ray> rays = cast_rays(scan, T_map_sensor, start, box);
  if (rays.empty()) return;
  // Between two end points, so inside `box`.
  const std::vector<CellIndex> surface = config_.surface_hit_weight > 0.0 ? surface_cells(steps) : std::vector<CellIndex>{};
  cells_.reserve(box);
  check(scan_count_ < UINT32_MAX, "OccupancyGrid::integrate_scan: more than 2^32 - 1 scans");
  ++scan_count_;
  apply_hits(rays, surface);  // first, so that a cell both hit and passed through gets the hit
  apply_misses(rays, start);
}

const std::vector<Eigen::Vector2d>& OccupancyGrid::beam_directions(const LaserScan& scan) {
  if (beam_directions_.size() != scan.size() || directions_angle_min_ != scan.angle_min ||
      directions_angle_increment_ != scan.angle_increment) {
    beam_directions_.resize(scan.size());
    for (std::size_t beam = 0; beam < scan.size(); ++beam) {
      beam_directions_[beam] = {std::cos(scan.angle(beam)), std::sin(scan.angle(beam))};
    }
    directions_angle_min_ = scan.angle_min;
    directions_angle_increment_ = scan.angle_increment;
  }
  return beam_directions_;
}

std::vector<OccupancyGrid::Ray> OccupancyGrid::cast_rays(const LaserScan& scan, const SE2& T_map_sensor,
                                                         CellIndex start, CellBox& box) {
  const std::vector<Eigen::Vector2d>& directions = beam_directions(scan);
  const Eigen::Matrix2d R = T_map_sensor.rotation();
  const Eigen::Vector2d& t = T_map_sensor.translation();
  std::vector<Ray> rays;
  rays.reserve(scan.size());
  const double range_max = std::min(scan.range_max, config_.max_range);
  for (std::size_t beam = 0; beam < scan.size(); ++beam) {
    const double range = scan.ranges[beam];
    if (!std::isfinite(range) || range < scan.range_min || range <= 0.0) continue;
    const bool hit = range < range_max;
    const double length = hit ? range : std::min(range, config_.max_clear_range);
    const Ray ray{geometry_.cell_of(t + R * (length * directions[beam])), hit};
    if (!hit && ray.end == start) continue;  // clears nothing
    box.extend(ray.end);
    rays.push_back(ray);
  }
  return rays;
}

// The cells between neighbouring returns on one surface. A wall seen at grazing incidence has its
// returns a metre or more apart, and a map that holds it as dots a beam apart pins a scan taken
// farther along to the viewpoint that drew them (its returns fall between the dots): the map
// claims to know the open axis of a corridor. Returns of neighbouring beams i and i + 1 are one
// surface when the step between them goes on along the line that leads up to it (the chord from up
// to four beams before i to i) and along the one that leads away from it (from i + 1 to up to four
// beams after): four returns or more in a line (core/point_cloud.hpp's continues_line). A depth
// edge, a mixed pixel between two surfaces, a lone return and a surface's last step are not; a
// doorway no beam fell into is filled, and cleared again by the beams through it. The cells are
// inferred, not seen: they get surface_hit_weight of a hit.
std::vector<OccupancyGrid::SurfaceStep> OccupancyGrid::surface_steps(const LaserScan& scan, const SE2& T_map_sensor) {
  constexpr std::size_t kReach = 4;  // beams in a chord (registration/degeneracy.cpp's too)
  const std::vector<Eigen::Vector2d>& directions = beam_directions(scan);
  const Eigen::Matrix2d R = T_map_sensor.rotation();
  const Eigen::Vector2d& t = T_map_sensor.translation();
  const double range_max = std::min(scan.range_max, config_.max_range);
  const std::size_t n = scan.size();
  std::vector<Eigen::Vector2d> end(n);
  std::vector<char> valid(n, 0);
  for (std::size_t beam = 0; beam < n; ++beam) {
    const double range = scan.ranges[beam];
    if (!std::isfinite(range) || range < scan.range_min || range <= 0.0 || range >= range_max) continue;
    end[beam] = t + R * (range * directions[beam]);  // as cast_rays
    valid[beam] = 1;
  }
  // The unit direction of the chord ending at `to` from the farthest valid return up to kReach
  // beams away in direction `side` (-1 before, +1 after), through valid returns only; none when
  // its neighbour is missing.
  const auto chord = [&](std::size_t to, int side) -> std::optional<Eigen::Vector2d> {
    std::size_t from = to;
    for (std::size_t k = 1; k <= kReach; ++k) {
      const std::ptrdiff_t b = static_cast<std::ptrdiff_t>(to) + side * static_cast<std::ptrdiff_t>(k);
      if (b < 0 || b >= static_cast<std::ptrdiff_t>(n) || !valid[static_cast<std::size_t>(b)]) break;
      from = static_cast<std::size_t>(b);
    }
    const Eigen::Vector2d d = end[to] - end[from];
    if (from == to || d.norm() < 1e-9) return std::nullopt;
    return d.normalized();
  };
  std::vector<SurfaceStep> steps;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (!valid[i] || !valid[i + 1]) continue;
    const Eigen::Vector2d step = end[i + 1] - end[i];
    // Ends within a cell along both axes lie in neighbouring cells at this and any coarser level.
    if (std::abs(step.x()) < config_.resolution && std::abs(step.y()) < config_.resolution) continue;
    const std::optional<Eigen::Vector2d> before = chord(i, -1);
    const std::optional<Eigen::Vector2d> after = chord(i + 1, +1);
    if (!(before && continues_line(*before, step) && after && continues_line(*after, -step))) continue;
    steps.push_back({end[i], end[i + 1]});
  }
  return steps;
}

// The cells strictly between each step's two end cells, on its Bresenham line.
std::vector<CellIndex> OccupancyGrid::surface_cells(const std::vector<SurfaceStep>& steps) const {
  std::vector<CellIndex> cells;
  for (const SurfaceStep& step : steps) {
    const CellIndex a = geometry_.cell_of(step.from);
    const CellIndex b = geometry_.cell_of(step.to);
    if (std::max(std::abs(a.x - b.x), std::abs(a.y - b.y)) <= 1) continue;  // nothing between them
    for_each_cell_before(a, b, [&](CellIndex cell) {
      if (cell != a) cells.push_back(cell);
    });
  }
  return cells;
}

void OccupancyGrid::apply_hits(const std::vector<Ray>& rays, const std::vector<CellIndex>& surface) {
  TileCursor cursor(cells_);
  CellBox touched;
  const auto hit = [&](CellIndex index, float log_odds) {
    OccupancyCell& cell = cursor(index);
    if (cell.last_scan == scan_count_) return;
    cell.log_odds = std::clamp(cell.log_odds + log_odds, log_odds_min_, log_odds_max_);  // Table 9.1, line 4
    cell.last_scan = scan_count_;
    touched.extend(index);
  };
  for (const Ray& ray : rays) {
    if (ray.hit) hit(ray.end, log_odds_hit_);
  }
  for (const CellIndex cell : surface) hit(cell, log_odds_surface_);
  cells_.mark_touched(touched);
}

void OccupancyGrid::apply_misses(const std::vector<Ray>& rays, CellIndex start) {
  const std::uint32_t stamp = scan_count_;
  const float miss = log_odds_miss_;
  const float low = log_odds_min_;
  for (const Ray& ray : rays) {
    cells_.update_ray(start, ray.end, [=](OccupancyCell& cell) {
      // Table 9.1, line 4, for a cell not yet updated by this scan (a miss only lowers l); branch-free.
      const float updated = std::max(cell.log_odds + miss, low);
      cell.log_odds = cell.last_scan == stamp ? cell.log_odds : updated;
      cell.last_scan = stamp;
    });
  }
}

OccupancyMap OccupancyGrid::to_occupancy_map() const {
  OccupancyMap map;
  map.resolution = config_.resolution;
  const CellBox& observed = observed_box();
  if (observed.empty()) return map;
  const CellIndex first{observed.min.x - 1, observed.min.y - 1};  // map cell (0, 0)
  const Eigen::Vector2d corner = geometry_.cell_corner(first);
  map.origin = SE2(corner.x(), corner.y(), 0.0);
  map.width = observed.width() + 2;
  map.height = observed.height() + 2;
  map.cells.assign(static_cast<std::size_t>(map.width) * map.height, OccupancyMap::kUnknown);
  constexpr int kTile = CellGrid::kTileSize;
  cells_.for_each_tile([&](CellIndex tile_first, const CellGrid::Tile& tile) {
    for (int ty = 0; ty < kTile; ++ty) {
      for (int tx = 0; tx < kTile; ++tx) {
        const OccupancyCell& cell = tile.cells[static_cast<std::size_t>(ty * kTile + tx)];
        if (cell.last_scan == 0) continue;  // observed cells all lie inside `observed`
        const double p = probability_from_log_odds(cell.log_odds);
        map.at(tile_first.x + tx - first.x, tile_first.y + ty - first.y) = static_cast<std::int8_t>(std::lround(100.0 * p));
      }
    }
  });
  return map;
}

std::size_t OccupancyGrid::memory_bytes() const { return sizeof(*this) - sizeof(cells_) + cells_.memory_bytes(); }

}  // namespace slam2d
