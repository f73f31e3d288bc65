// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/likelihood_field.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/grid/distance_transform.hpp"

namespace slam2d {

namespace {

void validate(const LikelihoodFieldConfig& config) {
  check_fields(config, "LikelihoodFieldConfig");
  check(config.z_rand / config.z_max >= 1e-300, "LikelihoodFieldConfig: z_rand / z_max underflows");
}

/// Margin (cells) around the source box: the outermost samples lie more than max_distance from
/// every source cell. Throws when the field would exceed kMaxDistanceTransformCells samples.
int margin_for(const LikelihoodFieldConfig& config, double resolution, int width, int height) {
  check(std::isfinite(resolution) && resolution > 0.0, "LikelihoodField: the resolution must be finite and positive");
  const double margin = std::ceil(config.max_distance / resolution) + 1.0;
  const double samples = (width + 2.0 * margin) * (height + 2.0 * margin);
  check(samples <= static_cast<double>(kMaxDistanceTransformCells),
        "LikelihoodField: the field would have more than 2^28 samples (max_distance " +
            std::to_string(config.max_distance) + " m at " + std::to_string(resolution) + " m per cell)");
  return static_cast<int>(margin);
}

}  // namespace

LikelihoodField::LikelihoodField(const OccupancyMap& map, const LikelihoodFieldConfig& config) : config_(config) {
  validate(config_);
  check(map.width >= 0 && map.height >= 0 &&
            map.cells.size() == static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height),
        "LikelihoodField: the map's cell count does not match its size");
  check(map.origin.vector().allFinite(), "LikelihoodField: the map's origin is not finite");
  const int m = margin_for(config_, map.resolution, map.width, map.height);
  if (map.width == 0 || map.height == 0) {
    set_geometry(map.origin, map.resolution, 0, 0);
    return;
  }
  margin_cells_ = m;
  set_geometry(map.origin * SE2(-m * map.resolution, -m * map.resolution, 0.0), map.resolution, map.width + 2 * m,
               map.height + 2 * m);
  std::vector<std::uint8_t> obstacles(static_cast<std::size_t>(width_) * height_, 0);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if (map.at(x, y) >= config_.occupied_threshold) {
        obstacles[static_cast<std::size_t>(y + m) * width_ + (x + m)] = 1;
      }
    }
  }
  build(obstacles);
}

LikelihoodField::LikelihoodField(const OccupancyGrid& grid, const CellBox& region, const LikelihoodFieldConfig& config)
    : config_(config) {
  validate(config_);
  const GridGeometry& geometry = grid.geometry();
  const int m = margin_for(config_, geometry.resolution, region.width(), region.height());
  if (region.empty()) {
    set_geometry(SE2(geometry.origin, 0.0), geometry.resolution, 0, 0);
    return;
  }
  margin_cells_ = m;
  const Eigen::Vector2d corner = geometry.cell_corner(region.min) - Eigen::Vector2d::Constant(m * geometry.resolution);
  set_geometry(SE2(corner, 0.0), geometry.resolution, region.width() + 2 * m, region.height() + 2 * m);
  std::vector<std::uint8_t> obstacles(static_cast<std::size_t>(width_) * height_, 0);
  for (int y = region.min.y; y <= region.max.y; ++y) {
    for (int x = region.min.x; x <= region.max.x; ++x) {
      const CellIndex cell{x, y};
      // The rounding of OccupancyGrid::to_occupancy_map, so both constructors agree.
      if (grid.is_known(cell) && std::lround(100.0 * grid.probability(cell)) >= config_.occupied_threshold) {
        obstacles[static_cast<std::size_t>(y - region.min.y + m) * width_ + (x - region.min.x + m)] = 1;
      }
    }
  }
  build(obstacles);
}

void LikelihoodField::set_geometry(const SE2& origin, double resolution, int width, int height) {
  origin_ = origin;
  resolution_ = resolution;
  inverse_resolution_ = 1.0 / resolution;
  cos_ = std::cos(origin.theta());
  sin_ = std::sin(origin.theta());
  width_ = width;
  height_ = height;
  u_limit_ = width - 1.0;
  v_limit_ = height - 1.0;
  inverse_two_sigma2_ = 1.0 / (2.0 * config_.sigma_hit * config_.sigma_hit);
  hit_scale_ = config_.z_hit / (std::sqrt(2.0 * std::numbers::pi) * config_.sigma_hit);
  random_density_ = config_.z_rand / config_.z_max;
  outside_distance_ = static_cast<float>(config_.max_distance);
  // Every beam likelihood lies in [random_density_, hit_scale_ + random_density_]; a product of
  // product_chunk_ of them stays within e^(+-600), far from double's limits (e^(+-708)).
  const double largest_log =
      std::max({std::abs(std::log(random_density_)), std::abs(std::log(hit_scale_ + random_density_)), 1.0});
  product_chunk_ = static_cast<std::size_t>(std::clamp(std::floor(600.0 / largest_log), 1.0, 32.0));
  distances_.clear();
}

void LikelihoodField::build(const std::vector<std::uint8_t>& obstacles) {
  const SquaredDistanceField squared = squared_distance_transform_of_sites(width_, height_, obstacles);
  distances_.resize(squared.squared_distances.size());
  for (std::size_t i = 0; i < distances_.size(); ++i) {
    // sqrt(inf) = inf for a map without obstacles: capped like every far cell.
    const double d = std::sqrt(squared.squared_distances[i]) * resolution_;
    distances_[i] = std::min(static_cast<float>(d), outside_distance_);
  }
}

double LikelihoodField::outside(const Eigen::Vector2d& point_map, Eigen::Vector2d* gradient_map) const {
  if (!point_map.allFinite()) {  // garbage in: NaN out, never a plausible distance
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    if (gradient_map != nullptr) *gradient_map = {kNaN, kNaN};
    return kNaN;
  }
  if (gradient_map != nullptr) gradient_map->setZero();
  return outside_distance_;
}

double LikelihoodField::scan_log_likelihood(const PointCloud2& points_robot, const SE2& T_map_robot) const {
  if (!T_map_robot.vector().allFinite()) throw Error("LikelihoodField::scan_log_likelihood: non-finite pose");
  const Eigen::Matrix2d R = T_map_robot.rotation();
  const Eigen::Vector2d& t = T_map_robot.translation();
  // Table 6.3, line 8, as a sum of logs. The beam likelihoods are multiplied in chunks short
  // enough that no product can under- or overflow (product_chunk_), and one log is taken per
  // chunk: the same sum to rounding, at a fraction of the logs.
  double log_likelihood = 0.0;
  const std::size_t n = points_robot.points.size();
  for (std::size_t first = 0; first < n; first += product_chunk_) {
    const std::size_t last = std::min(n, first + product_chunk_);
    double product = 1.0;
    for (std::size_t i = first; i < last; ++i) {
      const Point2& point = points_robot.points[i];
      if (!point.allFinite()) throw Error("LikelihoodField::scan_log_likelihood: non-finite end point");
      product *= beam_likelihood(R * point + t);
    }
    log_likelihood += std::log(product);
  }
  return log_likelihood;
}

}  // namespace slam2d
