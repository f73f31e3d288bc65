// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Range-finder sensor models for localization in a known map: S. Thrun, W. Burgard, D. Fox,
// "Probabilistic Robotics", 2005, Chapter 6.
// - The likelihood field (Sec. 6.4, Table 6.3): LocalizationMap::scan_log_likelihood, fast.
// - The beam model (Sec. 6.3, Table 6.1): ray casting in the map for the expected range z*, and a
//   mixture of a Gaussian hit around z*, an exponential of short readings (unexpected objects),
//   a point mass at the maximum range (no return) and a uniform of random readings.
// Both score a subset of the beams (`select_beams`): evenly spaced over the scan, as in AMCL's
// max_beams, since neighbouring beams are far from independent.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

/// The beams kept from one scan.
struct ScanBeams {
  std::vector<Eigen::Vector2d> points_robot;  // end points of the valid beams (no max-range readings), robot frame
  std::vector<double> ranges;                 // m, every kept beam, max-range readings as range_max
  std::vector<double> bearings;               // rad, of every kept beam, sensor frame
  double range_max = 0.0;                     // m
  SE2 T_robot_sensor;
};

/// Up to `max_beams` beams evenly spaced over the scan (> 0). Readings below range_min or
/// non-finite are dropped; readings at or beyond min(scan.range_max, usable_range) count as
/// max-range readings (in `ranges` only).
ScanBeams select_beams(const LaserScan& scan, int max_beams, double usable_range);

struct BeamModelConfig {
  double z_hit = 0.8;  // the four weights are normalised internally; not all zero
  double z_short = 0.05;
  double z_max = 0.05;
  double z_rand = 0.1;
  double sigma_hit = 0.2;
  double lambda_short = 0.1;
  double max_range_band = 0.1;
};

template <typename Fields>
void describe(Fields& f, BeamModelConfig& c) {
  f.number("z_hit", c.z_hit, "1", at_least(0), "weight of the Gaussian hit component");
  f.number("z_short", c.z_short, "1", at_least(0), "weight of the short-reading component");
  f.number("z_max", c.z_max, "1", at_least(0), "weight of the max-range component");
  f.number("z_rand", c.z_rand, "1", at_least(0), "weight of the uniform component");
  f.number("sigma_hit", c.sigma_hit, "m", greater_than(0), "standard deviation of the hit component");
  f.number("lambda_short", c.lambda_short, "1/m", greater_than(0), "rate of the short-reading component");
  f.number("max_range_band", c.max_range_band, "m", at_least(0),
           "readings within this of range_max count as max-range readings");
}

/// Throws Error for negative weights, all-zero weights or non-positive sigma / lambda.
void validate(const BeamModelConfig& config);

/// The range at which a ray from `origin` at bearing `angle` (map frame) first meets an occupied
/// cell (>= 65 %) of the map, walking the cells (Bresenham), or `max_range` if none. Unknown and
/// off-map cells do not stop the ray.
double cast_ray(const OccupancyMap& map, const Eigen::Vector2d& origin, double angle, double max_range);

/// Table 6.1: sum over the beams of log p(z_k | x, m) at T_map_robot.
double beam_model_log_likelihood(const OccupancyMap& map, const ScanBeams& beams, const SE2& T_map_robot,
                                 const BeamModelConfig& config);

}  // namespace slam2d
