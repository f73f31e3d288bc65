// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The likelihood field of a map: S. Thrun, W. Burgard, D. Fox, "Probabilistic Robotics", 2005,
// Section 6.4, Table 6.3 (likelihood_field_range_finder_model). Each beam end point is scored by
// its distance to the nearest obstacle: a Gaussian "hit" density mixed with a uniform density for
// random measurements; max-range readings carry no end point and are left out.
//
// The distance to the nearest occupied cell is computed once by the exact Euclidean distance
// transform (distance_transform.hpp, Felzenszwalb and Huttenlocher 2012), capped at
// max_distance, and stored densely (float) at the centres of the cells of the map's box grown by
// a margin of ceil(max_distance / resolution) + 1 cells, so that the outermost samples all equal
// max_distance. Distances are between cell centres: an occupied cell's own centre is at 0.
//
// Queries at continuous map-frame points interpolate the samples bilinearly: the distance is
// exact at cell centres and continuous everywhere. The gradient is the exact derivative of that
// interpolant (what Gauss-Newton needs to be consistent with the value): inside a cell it is
// continuous, and each component is continuous across the cell edges parallel to it; across an
// edge perpendicular to it, it may jump by the second difference of the samples (zero where the
// field is linear). Points outside the field get max_distance and a zero gradient, which joins
// the inside continuously. A query is a few nanoseconds: no allocation, no hashing.

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/grid/grid_geometry.hpp"
#include "slam2d/grid/occupancy_grid.hpp"

namespace slam2d {

struct LikelihoodFieldConfig {
  double max_distance = 2.0;
  int occupied_threshold = 65;  // map_saver's 65
  // The sensor model of Table 6.3:
  double sigma_hit = 0.2;
  double z_hit = 0.95;
  double z_rand = 0.05;
  double z_max = 30.0;  // z_rand / z_max must not underflow
};

template <typename Fields>
void describe(Fields& f, LikelihoodFieldConfig& c) {
  f.number("max_distance", c.max_distance, "m", greater_than(0),
           "distances are capped here; points outside the field get it");
  f.number("occupied_threshold", c.occupied_threshold, "%", between(1, 100), "cells with occupancy >= this are obstacles");
  f.number("sigma_hit", c.sigma_hit, "m", greater_than(0), "standard deviation of an end point's distance to the obstacle");
  f.number("z_hit", c.z_hit, "1", at_least(0), "weight of the Gaussian hit density");
  f.number("z_rand", c.z_rand, "1", greater_than(0), "weight of the uniform density of random readings");
  f.number("z_max", c.z_max, "m", greater_than(0), "the sensor's maximum range; the uniform density is 1 / z_max");
}

/// `config` with another sigma_hit, its distance cap widened to at least 3 sigma_hit (a wider,
/// smoother field: the Markov grid's cells, the global pose search's coarse poses).
inline LikelihoodFieldConfig with_sigma_hit(LikelihoodFieldConfig config, double sigma_hit) {
  config.sigma_hit = sigma_hit;
  config.max_distance = config.max_distance > 3.0 * sigma_hit ? config.max_distance : 3.0 * sigma_hit;
  return config;
}

class LikelihoodField {
 public:
  /// The field of a finished map (any origin pose): cells >= occupied_threshold are obstacles,
  /// unknown (-1) and other cells are not. Throws Error for an invalid configuration (ranges on
  /// LikelihoodFieldConfig), a map whose cell count is not width * height, a non-finite origin or
  /// non-positive resolution, or a field of more than kMaxDistanceTransformCells samples.
  explicit LikelihoodField(const OccupancyMap& map, const LikelihoodFieldConfig& config = {});
  /// The field of a region of an occupancy grid (e.g. grid.observed_box()): known cells with
  /// round(100 p) >= occupied_threshold are obstacles, as in grid.to_occupancy_map(). An empty
  /// region gives an empty field (every query returns max_distance). Errors as above.
  LikelihoodField(const OccupancyGrid& grid, const CellBox& region, const LikelihoodFieldConfig& config = {});

  /// Distance (m) from a map-frame point to the nearest obstacle, bilinearly interpolated and
  /// capped at max_distance; max_distance outside the field, NaN for a non-finite point (distances
  /// are stored as float: max_distance too is rounded to float). `gradient_map` (if not null)
  /// receives d(distance)/d(point) in the map frame (zero outside the field).
  double distance(const Eigen::Vector2d& point_map, Eigen::Vector2d* gradient_map = nullptr) const;
  /// exp(-d^2 / (2 sigma_hit^2)) at a map-frame point: 1 on an obstacle, in (0, 1].
  double likelihood(const Eigen::Vector2d& point_map) const {
    const double d = distance(point_map);
    return std::exp(-d * d * inverse_two_sigma2_);
  }
  /// Table 6.3, line 8: z_hit prob(d, sigma_hit) + z_rand / z_max, a density in 1/m, where
  /// prob(d, sigma) is the zero-mean normal density.
  double beam_likelihood(const Eigen::Vector2d& point_map) const {
    const double d = distance(point_map);
    return hit_scale_ * std::exp(-d * d * inverse_two_sigma2_) + random_density_;
  }
  /// log q of Table 6.3: the sum of log beam_likelihood over a scan's end points, given in the
  /// robot frame (e.g. to_point_cloud(scan, ScanFrame::kRobot), which leaves out max-range
  /// readings), placed at T_map_robot. 0 for an empty cloud. Throws Error for a non-finite pose or point.
  double scan_log_likelihood(const PointCloud2& points_robot, const SE2& T_map_robot) const;

  /// Samples along x and y; sample (x, y) is the distance at the centre of field cell (x, y).
  int width() const { return width_; }
  int height() const { return height_; }
  double sample(int x, int y) const { return distances_[static_cast<std::size_t>(y) * width_ + x]; }
  /// m per cell, as the source map.
  double resolution() const { return resolution_; }
  /// Pose of the lower-left corner of field cell (0, 0) in the map frame.
  const SE2& origin() const { return origin_; }
  /// The map-frame centre of field cell (x, y).
  Eigen::Vector2d cell_center(int x, int y) const {
    return origin_.act(Eigen::Vector2d((x + 0.5) * resolution_, (y + 0.5) * resolution_));
  }
  /// Cells of the margin added on each side of the source box.
  int margin_cells() const { return margin_cells_; }
  const LikelihoodFieldConfig& config() const { return config_; }
  std::size_t memory_bytes() const { return sizeof(*this) + distances_.capacity() * sizeof(float); }

 private:
  /// Computes the capped distances from obstacle flags over the whole field (row-major).
  void build(const std::vector<std::uint8_t>& obstacles);
  void set_geometry(const SE2& origin, double resolution, int width, int height);
  double outside(const Eigen::Vector2d& point_map, Eigen::Vector2d* gradient_map) const;

  LikelihoodFieldConfig config_;
  SE2 origin_;
  double resolution_ = 0.05;
  double inverse_resolution_ = 20.0;
  double cos_ = 1.0;  // of origin_.theta()
  double sin_ = 0.0;
  int width_ = 0;
  int height_ = 0;
  int margin_cells_ = 0;
  double u_limit_ = -1.0;  // width_ - 1: interpolation needs samples i and i + 1
  double v_limit_ = -1.0;
  double inverse_two_sigma2_ = 0.0;
  double hit_scale_ = 0.0;       // z_hit / (sqrt(2 pi) sigma_hit), 1/m
  double random_density_ = 0.0;  // z_rand / z_max, 1/m
  std::size_t product_chunk_ = 1;  // beam likelihoods multiplied before one log (scan_log_likelihood)
  float outside_distance_ = 2.0f;  // m, max_distance rounded to float like the samples
  std::vector<float> distances_;   // m, row-major, capped at outside_distance_
};

inline double LikelihoodField::distance(const Eigen::Vector2d& point_map, Eigen::Vector2d* gradient_map) const {
  // Field coordinates in samples: the centre of field cell (i, j) is at (i, j).
  const double dx = point_map.x() - origin_.x();
  const double dy = point_map.y() - origin_.y();
  const double u = (cos_ * dx + sin_ * dy) * inverse_resolution_ - 0.5;
  const double v = (cos_ * dy - sin_ * dx) * inverse_resolution_ - 0.5;
  if (!(u >= 0.0 && v >= 0.0 && u < u_limit_ && v < v_limit_)) return outside(point_map, gradient_map);
  const int i = static_cast<int>(u);  // u >= 0: truncation is floor
  const int j = static_cast<int>(v);
  const double fu = u - i;
  const double fv = v - j;
  const float* s = distances_.data() + static_cast<std::size_t>(j) * width_ + i;
  const double d00 = s[0];
  const double d10 = s[1];
  const double d01 = s[width_];
  const double d11 = s[width_ + 1];
  const double bottom = d00 + fu * (d10 - d00);
  const double top = d01 + fu * (d11 - d01);
  if (gradient_map != nullptr) {
    const double g_u = ((1.0 - fv) * (d10 - d00) + fv * (d11 - d01)) * inverse_resolution_;
    const double g_v = (top - bottom) * inverse_resolution_;
    *gradient_map = {cos_ * g_u - sin_ * g_v, sin_ * g_u + cos_ * g_v};  // field frame -> map frame
  }
  return bottom + fv * (top - bottom);
}

}  // namespace slam2d
