// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Hybrid localization, as proposed by J.-S. Gutmann, W. Burgard, D. Fox, K. Konolige, "An
// experimental comparison of localization methods", IROS 1998 (Sec. VI: combine the robustness
// of grid-based Markov localization with the accuracy and efficiency of the scan-matching
// Kalman filter): a coarse Markov grid (markov_grid.hpp) runs all the time and watches
// plausibility; the EKF (ekf.hpp) runs while the pose is unique and takes its prior from the
// grid. The grid takes over when
//   - the EKF reports itself lost (its matches keep failing the gates), or
//   - the grid is localized (unique) at a pose more than max_disagreement from the EKF's;
// and the EKF is restarted from the grid's estimate as soon as the grid is unique again.
// The estimate reported is the EKF's while it runs, else the grid's.
// Where the two disagree, the one the scan supports wins (issue 40's consistency test): the grid
// takes over from a running EKF only if the scan fits the map significantly better at its pose
// than at the EKF's. The fit is the plausibility (the share of end points near an obstacle) at
// the scan matched from each pose (`matcher`: the grid's pose is known only to a cell); better by
// `takeover_z` standard errors of the difference of the two shares (binomial, n end points). A
// grid that a degraded scanner led astray (spurious short readings) so no longer resets a tracking
// EKF to its wrong place; after a kidnap the EKF's pose explains little and the grid wins.

#include <cstddef>
#include <string>

#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/markov_grid.hpp"

namespace slam2d {

struct HybridConfig {
  MarkovGridConfig grid{.resolution = 0.4, .angles = 36, .max_beams = 30, .sigma_hit = 0.5, .update_distance = 0.4,
                        .update_angle = 0.1745};
  EkfConfig ekf{};
  double max_disagreement = 1.5;
  LikelihoodFieldMatchConfig matcher{};
  double takeover_z = 2.0;
};

template <typename Fields>
void describe(Fields& f, HybridConfig& c) {
  f.section("grid", c.grid, "the Markov grid that keeps the global belief");
  f.section("ekf", c.ekf, "the EKF that tracks");
  f.number("max_disagreement", c.max_disagreement, "m", greater_than(0),
           "the grid takes over when localized farther than this from the EKF ...");
  f.section("matcher", c.matcher, "... and the scan, matched from each of the two poses, ...");
  f.number("takeover_z", c.takeover_z, "1", at_least(0),
           "... fits the map better at the grid's by this many standard errors of the difference");
}

class HybridLocalization : public Localizer {
 public:
  HybridLocalization(const LocalizationMap& map, const HybridConfig& config = {});

  void initialize(const SE2& T_map_robot, const Covariance3& covariance);
  void initialize_global();

  LocalizationEstimate update(const SE2& T_odom_robot, const LaserScan& scan) override;
  std::size_t sensor_updates() const override { return sensor_updates_; }
  std::string name() const override { return "hybrid"; }

  bool ekf_active() const { return ekf_active_; }
  std::size_t handovers() const { return handovers_; }  // grid -> EKF starts
  const EkfLocalization& ekf() const { return ekf_; }
  const MotionNoiseLearner* motion_noise() const override { return ekf_.motion_noise(); }
  const MarkovGridLocalization& grid() const { return grid_; }

 private:
  /// Whether the scan fits the map significantly better at `grid_pose` than at `ekf_pose` (header).
  bool grid_explains_better(const LaserScan& scan, const SE2& grid_pose, const SE2& ekf_pose) const;

  const LocalizationMap& map_;
  HybridConfig config_;
  MarkovGridLocalization grid_;
  EkfLocalization ekf_;
  bool ekf_active_ = false;
  std::size_t handovers_ = 0;
  std::size_t sensor_updates_ = 0;
};

}  // namespace slam2d
