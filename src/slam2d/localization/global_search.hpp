// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The coarse pass of a coarse-to-fine global localization: every pose of a regular grid over the
// map's free space and the headings is scored by the likelihood field (Thrun et al. 2005, Table
// 6.3), the best are kept and scored again by the next scans (each hypothesis carried along the
// odometry since the first scan, log-likelihoods summed), and the particle filter is then seeded
// around the best. This is the exhaustive correlative search of E. Olson, "Real-time
// correlative scan matching", ICRA 2009, run over the whole map instead of a window, and what
// gives a particle filter at least one particle in the basin of the true pose whatever the size
// of the building: a uniform start of N particles over A m^2 of free space has a particle within
// r m and dtheta of the truth with probability about 1 - exp(-N pi r^2 dtheta / (2 pi A)), which
// for 5000 particles, r = 0.25 m, dtheta = 5 deg and 500 m^2 (Intel) is 0.07.
//
// Sizing and cost: the grid has step_xy m between positions (positions on the free cells of the
// map, subsampled) and step_theta between headings; when that grid would exceed max_poses the
// position step grows until it does not, so the first scan costs at most max_poses x max_beams
// table reads (~1 ns each) whatever the map, and the later ones keep x max_beams. The search
// scores with its own, wider likelihood field (sigma_hit), so that a grid pose half a step from
// the truth still explains the scan: the width is at least the grid's step.
//
// Deterministic: the grid and the order of the hypotheses depend on the map and the scans only;
// ties are broken by the grid index; the seeding draws from the caller's Rng.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/localization/localization_map.hpp"

namespace slam2d {

struct GlobalSearchConfig {
  double step_xy = 0.25;
  double step_theta = 0.0873;  // 5 deg, 72 headings
  std::size_t max_poses = 4'000'000;
  double sigma_hit = 0.4;
  int max_beams = 60;
  std::size_t keep = 100'000;
  int updates = 5;
};

template <typename Fields>
void describe(Fields& f, GlobalSearchConfig& c) {
  f.number("step_xy", c.step_xy, "m", greater_than(0), "the finest position step of the pose grid");
  f.number("step_theta", c.step_theta, "rad", open_closed(0, std::numbers::pi), "the heading step");
  f.number("max_poses", c.max_poses, "1", between(1, 4294967295.0),
           "budget of grid poses scored by the first scan; step_xy grows to stay within (fits 32 bits)");
  f.number("sigma_hit", c.sigma_hit, "m", greater_than(0),
           "the search's likelihood-field sigma (raised to the grid's step if below)");
  f.number("max_beams", c.max_beams, "1", at_least(1), "beams scored per scan");
  f.number("keep", c.keep, "1", at_least(1), "hypotheses kept after the first scan");
  f.number("updates", c.updates, "1", at_least(1), "sensor updates scored before the filter is seeded");
}

/// Throws Error for values outside the ranges above.
void validate(const GlobalSearchConfig& config);

class GlobalPoseSearch {
 public:
  /// Builds the pose grid and the search's likelihood field from the map (which must outlive it).
  GlobalPoseSearch(const LocalizationMap& map, const GlobalSearchConfig& config = {});

  /// Forgets the scans scored so far.
  void restart();
  /// Scores the hypotheses by one scan (end points in the robot frame) taken after the robot moved
  /// T_start_robot since the first scan, by the odometry. The first call scores the whole grid and
  /// keeps the best `keep`.
  void add_scan(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_start_robot);
  /// The scans scored since restart().
  int scans() const { return scans_; }
  bool done() const { return scans_ >= config_.updates; }

  /// The candidate places: the best `count` hypotheses grouped, best first, into places of
  /// hypotheses within radius_xy (m) and radius_theta (rad) of the place's best one; at most
  /// max_places. The places share `particles` equally (at least one each): poses drawn from each
  /// place's members, best first and cycling, each uniformly within its grid cell (+- half a step
  /// in x, y and heading), at the robot's current pose.
  std::vector<std::vector<SE2>> seed_places(std::size_t count, std::size_t max_places, std::size_t particles,
                                            double radius_xy, double radius_theta, Rng& rng) const;
  /// The best hypothesis at the robot's current pose.
  SE2 best() const;
  /// Mean and covariance of the best `count` hypotheses at the current pose (equal weights): how
  /// far apart the candidates still are.
  void spread(std::size_t count, SE2* mean, Covariance3* covariance) const;

  // The grid, for reports and tests.
  std::size_t positions() const { return positions_.size(); }
  int headings() const { return headings_; }
  double step_xy() const { return step_xy_; }
  std::size_t grid_poses() const { return positions_.size() * static_cast<std::size_t>(headings_); }
  std::size_t hypotheses() const { return hypotheses_.size(); }
  const LocalizationMap& field_map() const { return field_map_; }
  const GlobalSearchConfig& config() const { return config_; }

 private:
  SE2 grid_pose(std::size_t index) const;  // position index * headings + heading index
  void score_grid(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_start_robot);
  std::vector<std::size_t> ranking() const;  // hypothesis indices, best first
  SE2 jittered(std::size_t hypothesis, Rng& rng) const;  // within its grid cell, at the current pose

  GlobalSearchConfig config_;
  LocalizationMap field_map_;  // the map with the search's sigma_hit
  std::vector<Eigen::Vector2d> positions_;
  int headings_ = 0;
  double step_xy_ = 0.0;
  double heading_step_ = 0.0;
  std::vector<SE2> hypotheses_;  // poses at the first scan
  std::vector<double> scores_;   // summed log-likelihoods
  std::vector<std::uint32_t> grid_index_;
  SE2 T_start_robot_;
  int scans_ = 0;
};

}  // namespace slam2d
