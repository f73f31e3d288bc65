// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Grid-based Markov localization: W. Burgard, D. Fox, D. Hennig, T. Schmidt, "Estimating the
// absolute position of a mobile robot using position probability grids", AAAI 1996; D. Fox,
// W. Burgard, S. Thrun, "Markov localization for mobile robots in dynamic environments", JAIR 11,
// 1999 (the fine-grained grid and the selective update); compared with the EKF in Gutmann et al.
// 1998. The belief is a histogram over (x, y, theta) covering the map's box: `resolution` m
// cells, `angles` headings; only cells whose centre is a free map cell carry probability.
//
// - Motion (once the robot has moved update_distance or turned update_angle): the accumulated
//   odometry (rot1, trans, rot2) moves each heading layer by its own displacement, the mass split
//   over the 8 neighbouring cells in (x, y, theta) by the fractional offsets (a bilinear splat: no
//   rounding bias), then the belief is convolved with the motion noise: m passes of a [1 2 1] / 4
//   kernel along x and y and m_theta passes along theta, each pass adding a variance of 1/2 cell^2
//   (1/2 layer^2), as many as cover the odometry motion model's noise for this control
//   (motion_model.hpp: the translation variance and trans^2 var(rot1) across, var(rot1) +
//   var(rot2) in heading), at least one (the grid's own quantisation). The model's noise is
//   scaled by what scan matches against the map show of the odometry (motion_noise, as MCL's).
// - Sensor: Bayes' rule with the likelihood field over max_beams beams (its own sigma_hit, wider
//   than the particle filter's, since a pose is known only to a cell), then normalisation. Cells
//   below prune_threshold of the maximum are set to zero; once localized the threshold rises to
//   selective_threshold and only cells above it are evaluated (the selective update: the cost
//   then follows the region that carries the mass, not the map).
// - A lost grid (LocalizationStatus) restarts from the uniform belief: global relocalization.
// The estimate is the mean of the mass within 1 m and 0.5 rad of the most probable cell; the
// covariance is the spread of the whole belief about it (so two modes show as a wide
// covariance, never as a confident pose), plus the cell's own quantisation.

#include <cstddef>
#include <string>
#include <vector>

#include "slam2d/core/covariance.hpp"
#include "slam2d/localization/localization_map.hpp"
#include "slam2d/localization/localizer.hpp"
#include "slam2d/localization/motion_model.hpp"

namespace slam2d {

struct MarkovGridConfig {
  double resolution = 0.2;
  int angles = 72;  // 5 deg
  int max_beams = 30;
  double usable_range = 30.0;
  double sigma_hit = 0.4;
  double update_distance = 0.2;
  double update_angle = 0.0873;  // 5 deg
  double prune_threshold = 1e-9;
  double selective_threshold = 1e-5;
  double estimate_radius = 1.0;
  OdometryMotionConfig motion{};
  // The odometry's noise learnt from scan matches against the map at the estimate while localized,
  // as MCL's (MotionNoiseLearner, motion_model.hpp): it only widens the motion convolution.
  MotionNoiseLearningConfig motion_noise{.min_scale = 1.0};
  LikelihoodFieldMatchConfig motion_noise_matcher{};
  LocalizationStatusConfig status{};
};

template <typename Fields>
void describe(Fields& f, MarkovGridConfig& c) {
  f.number("resolution", c.resolution, "m", greater_than(0), "cell size of the belief");
  f.number("angles", c.angles, "1", at_least(4), "heading layers");
  f.number("max_beams", c.max_beams, "1", at_least(1), "beams scored per update");
  f.number("usable_range", c.usable_range, "m", greater_than(0), "longer readings are max-range readings");
  f.number("sigma_hit", c.sigma_hit, "m", greater_than(0), "likelihood-field sigma of the grid's sensor model");
  f.number("update_distance", c.update_distance, "m", at_least(0), "filter update once the robot moved this far ...");
  f.number("update_angle", c.update_angle, "rad", at_least(0), "... or turned this much");
  f.number("prune_threshold", c.prune_threshold, "1", closed_open(0, 1), "of the maximum: cells below are dropped");
  f.number("selective_threshold", c.selective_threshold, "1", closed_open(0, 1),
           "of the maximum: once localized, only cells above are updated");
  f.number("estimate_radius", c.estimate_radius, "m", greater_than(0), "mass around the mode that makes the estimate");
  f.section("motion", c.motion, "the noise the motion convolution covers");
  f.section("motion_noise", c.motion_noise, "the motion noise's scales learnt from scan matches while localized");
  f.section("motion_noise_matcher", c.motion_noise_matcher, "the scan match at the estimate that motion_noise learns from");
  f.section("status", c.status, "when the estimate counts as localized or lost");
}

/// Throws Error for values outside the ranges above.
void validate(const MarkovGridConfig& config);

class MarkovGridLocalization : public Localizer {
 public:
  /// Builds its own likelihood field (config.sigma_hit) from the map.
  MarkovGridLocalization(const LocalizationMap& map, const MarkovGridConfig& config = {});

  /// A Gaussian belief around a pose.
  void initialize(const SE2& T_map_robot, const Covariance3& covariance);
  /// The uniform belief over the free cells.
  void initialize_global();

  LocalizationEstimate update(const SE2& T_odom_robot, const LaserScan& scan) override;
  std::size_t sensor_updates() const override { return sensor_updates_; }
  std::string name() const override { return "markov"; }
  const MotionNoiseLearner* motion_noise() const override { return &motion_noise_; }

  int width() const { return width_; }
  int height() const { return height_; }
  /// Cells with non-zero probability.
  std::size_t active_cells() const;
  /// Cells evaluated by the last sensor update.
  std::size_t evaluated_last() const { return evaluated_last_; }
  std::size_t memory_bytes() const;

 private:
  std::size_t index(int k, int y, int x) const {
    return (static_cast<std::size_t>(k) * height_ + y) * width_ + x;
  }
  SE2 cell_pose(int k, int y, int x) const;
  void motion_update(const OdometryControl& u);
  /// Binomial passes along x and y (`xy_passes`) and along theta (`theta_passes`).
  void blur(int xy_passes, int theta_passes);
  void sensor_update(const std::vector<Eigen::Vector2d>& points_robot);
  void normalize();
  std::size_t argmax() const;  // the most probable cell (within the box)
  LocalizationEstimate summarize(const std::vector<Eigen::Vector2d>& points_robot);

  struct CellRange {
    int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  // inclusive; every cell outside has zero probability
  };

  const LocalizationMap& map_;
  MarkovGridConfig config_;
  CellRange box_;
  LocalizationMap sensor_map_;  // the map with the grid's own sigma_hit
  SE2 T_map_grid_;              // the grid's frame: the map's cell axes
  int width_ = 0;
  int height_ = 0;
  double angle_step_ = 0.0;
  std::vector<std::uint8_t> free_;  // width * height
  std::vector<float> belief_;       // angles * height * width
  std::vector<float> scratch_;
  std::vector<float> log_likelihoods_;  // of the evaluated cells (float: half the memory of the largest array)
  bool initialized_ = false;
  bool started_ = false;
  SE2 odom_at_update_;
  LocalizationEstimate estimate_;
  LocalizationStatus status_;
  MotionNoiseLearner motion_noise_;
  std::size_t sensor_updates_ = 0;
  std::size_t evaluated_last_ = 0;
};

}  // namespace slam2d
