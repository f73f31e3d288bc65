// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Monte Carlo localization: F. Dellaert, D. Fox, W. Burgard, S. Thrun, "Monte Carlo localization
// for mobile robots", ICRA 1999; as Table 8.2 / 8.3 of S. Thrun, W. Burgard, D. Fox,
// "Probabilistic Robotics", 2005, with
// - KLD-sampling: D. Fox, "Adapting the sample size in particle filters through KLD-sampling",
//   IJRR 22(12), 2003: the particle count n = (k - 1) / (2 eps) (1 - 2 / (9 (k - 1)) +
//   sqrt(2 / (9 (k - 1))) z)^3 (Eq. 10), k the number of histogram bins with support;
// - random-sample injection driven by the short- and long-term average likelihood: J.-S.
//   Gutmann, D. Fox, "An experimental comparison of localization methods continued", IROS 2002
//   (Table 8.3, Augmented_MCL): w_slow += a_slow (w_avg - w_slow), w_fast += a_fast (w_avg -
//   w_fast), each resampled particle replaced by a random free pose with probability
//   max(0, 1 - w_fast / (injection_ratio w_slow)), at most max_injection. This is what lets a
//   kidnapped robot recover. (injection_ratio = 1 is the book's rule; 0.7 keeps a scene that is
//   only partly explained, people or moved furniture, from seeding look-alike places.)
//
// Deviation, on purpose: the random poses do not enter the tracked set directly. They form a
// second set, the recovery hypotheses: max_particles poses, seeded uniformly when injection
// starts, then at each step resampled among themselves with each one replaced by a random pose
// with the same probability; moved and weighed with the same odometry and scans. It replaces the
// tracked set only when, for takeover_updates updates in a row, it explains the scan better than
// the tracked set (weighted mean per-beam likelihood) and its best pose is plausible
// (status.min_plausibility of the end points near obstacles), as the status would call it
// localized; the two sets then trade places, so a wrong takeover can be undone. A searching set
// is dropped recovery_updates sensor updates after the last injection, a displaced one
// displaced_updates after the takeover, unless it explains the scan better than the tracked set. Under the book's rule one random pose that fits a single scan better
// than a tracked set passing an unmapped or changed part of the map takes the whole filter
// away: on FR079 a run without injection stays within 0.36 m of the truth, while every
// injection setting jumped 5-35 m to look-alike corridors. A kidnapped robot's tracked set
// explains nothing, so the recovery set takes over as soon as it has found the place.
//
// Global start (initialize_global), coarse to fine, sized by the map:
// 1. Coarse pass (global_search.hpp): the first global.updates sensor updates score a grid of
//    poses over the whole free space (0.25 m, 5 deg; coarser when the grid would exceed
//    global.max_poses) with a wide likelihood field, each carried along the odometry; the best
//    global.keep survive the first scan. Its cost is bounded by max_poses x beams, whatever the map.
// 2. Places: the best max_particles hypotheses are grouped into at most max_places places
//    (place_radius_xy, place_radius_theta), and the particles are shared equally among them.
// 3. Clustered particle filter (A. Milstein, J. N. Sanchez, E. T. Williamson, "Robust global
//    localization using clustered particle filtering", AAAI 2002): each place resamples within
//    itself to an equal share, so a place cannot die because another explained a few scans a
//    little better; its evidence is the sum over the updates of the log of the mean likelihood
//    of its particles (p(z | place)), counted once the places have settled on their local best
//    pose (place_settle_updates). A place place_margin below the best is dropped, once the robot
//    has driven place_min_travel since seeding (a turn on the spot shows one view, which a
//    degraded scanner can match at a wrong place); places whose means meet merge. The filter is
//    not localized while more than one place is left: it reports converged only when a single
//    place dominates. Then plain MCL runs, KLD-sampling shrinks the set.
//
// One filter step (`update`): the odometry since the last filter update is accumulated; once the
// robot has moved update_distance or turned update_angle, the particles are moved by samples of
// the odometry motion model (motion_model.hpp, Table 5.6), weighed by the likelihood field
// (LocalizationMap::scan_log_likelihood) over max_beams beams, summarised (weighted mean and
// covariance), then resampled by low-variance resampling (Table 4.4) to the KLD count, with
// injection. Between filter updates the estimate follows the odometry.
//
// Localized / lost (localizer.hpp) uses, besides the spread and the fraction of explained end
// points, Gutmann & Fox's signal itself: w_fast < min_likelihood_ratio w_slow counts as an
// implausible step (a compact particle cloud in a wrong but similar place is not "localized"),
// and so does a recovery set that is still searching (see above).
//
// Deviations, on purpose: w_avg is the mean over particles of the per-beam geometric mean
// likelihood exp(log p(z | x) / beams), scale-free where the product over beams would under- or
// overflow; w_slow and w_fast start at the first w_avg (so a global start injects nothing until
// the likelihood drops). The KLD bin count k is taken from a low-variance draw of the current
// particle count before the final draw (an upper bound of the k a sequential draw would see).

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/localization/global_search.hpp"
#include "slam2d/localization/localization_map.hpp"
#include "slam2d/localization/localizer.hpp"
#include "slam2d/localization/motion_model.hpp"
#include "slam2d/localization/sensor_model.hpp"
#include "slam2d/registration/likelihood_field_match.hpp"

namespace slam2d {

enum class SensorModelKind { kLikelihoodField, kBeam };
constexpr auto choices(SensorModelKind) {
  return std::array{Choice{"likelihood_field", SensorModelKind::kLikelihoodField}, Choice{"beam", SensorModelKind::kBeam}};
}

struct MclConfig {
  OdometryMotionConfig motion{};
  SensorModelKind sensor = SensorModelKind::kLikelihoodField;
  BeamModelConfig beam{};
  int max_beams = 60;
  // p(z | x)^exponent: neighbouring beams are not independent, and a sharper posterior than the
  // map supports jumps to look-alike places.
  double likelihood_exponent = 1.0;
  double usable_range = 30.0;
  std::size_t min_particles = 500;
  std::size_t max_particles = 5000;  // >= min_particles
  GlobalSearchConfig global{};
  // The places a global start tracks side by side (clustered particle filter, see the header):
  std::size_t max_places = 200;
  double place_radius_xy = 1.0;
  double place_radius_theta = 0.5;
  // One end point explained at 0 m instead of unexplained is log(1.9 / 0.0017) = 7: 40 is about 6
  // end points.
  double place_margin = 40.0;
  int place_settle_updates = 10;
  // The place radius; picked on Intel with degraded scanners (docs/methods/localization.md).
  double place_min_travel = 1.0;
  bool kld_sampling = true;
  double kld_epsilon = 0.05;
  double kld_z = 2.326;  // delta = 0.01
  double kld_bin_xy = 0.5;
  double kld_bin_theta = 0.1745;  // 10 deg
  double update_distance = 0.1;
  double update_angle = 0.1;
  bool augmented = true;
  double alpha_slow = 0.01;
  double alpha_fast = 0.3;  // > alpha_slow
  double max_injection = 0.2;
  double injection_ratio = 0.7;
  double min_likelihood_ratio = 0.5;
  int takeover_updates = 30;
  int recovery_updates = 10;
  int displaced_updates = 100;
  // The odometry's noise learnt from scan matches against the map at the estimate while localized
  // (MotionNoiseLearner, motion_model.hpp; the match: registration/likelihood_field_match.hpp).
  // It only widens the model: a particle set needs more spread than the odometry's own noise (its
  // sensor model is sharper than the map supports), so the configured model is the floor.
  MotionNoiseLearningConfig motion_noise{.min_scale = 1.0};
  LikelihoodFieldMatchConfig motion_noise_matcher{};
  LocalizationStatusConfig status{};
  std::uint64_t seed = 1;
};

template <typename Fields>
void describe(Fields& f, MclConfig& c) {
  f.section("motion", c.motion, "the sampled odometry motion model");
  f.choice("sensor", c.sensor, "the sensor model");
  f.section("beam", c.beam, "for sensor: beam");
  f.number("max_beams", c.max_beams, "1", at_least(1), "beams scored per scan");
  f.number("likelihood_exponent", c.likelihood_exponent, "1", open_closed(0, 1), "p(z | x)^exponent");
  f.number("usable_range", c.usable_range, "m", greater_than(0), "longer readings are treated as max-range readings");
  f.number("min_particles", c.min_particles, "1", at_least(1), "fewest particles (KLD sampling)");
  f.number("max_particles", c.max_particles, "1", at_least(1),
           ">= min_particles; also the count a global start is seeded with");
  f.section("global", c.global, "the coarse pass of a global start (global_search.hpp)");
  f.number("max_places", c.max_places, "1", at_least(1), "candidate places seeded from the coarse pass");
  f.number("place_radius_xy", c.place_radius_xy, "m", greater_than(0),
           "hypotheses this close (and within place_radius_theta) are one place");
  f.number("place_radius_theta", c.place_radius_theta, "rad", greater_than(0), "see place_radius_xy");
  f.number("place_margin", c.place_margin, "log-likelihood", greater_than(0), "a place this far below the best is dropped");
  f.number("place_settle_updates", c.place_settle_updates, "1", at_least(0),
           "updates after seeding before the places' evidence counts (they settle on their best pose)");
  f.number("place_min_travel", c.place_min_travel, "m", at_least(0),
           "no place is dropped before the robot drove this far since seeding");
  f.flag("kld_sampling", c.kld_sampling, "false: always max_particles");
  f.number("kld_epsilon", c.kld_epsilon, "1", greater_than(0), "bound on the KL divergence (Fox 2003)");
  f.number("kld_z", c.kld_z, "1", any_value(), "upper 1 - delta quantile of N(0, 1)");
  f.number("kld_bin_xy", c.kld_bin_xy, "m", greater_than(0), "histogram bin size");
  f.number("kld_bin_theta", c.kld_bin_theta, "rad", greater_than(0), "histogram bin size in heading");
  f.number("update_distance", c.update_distance, "m", at_least(0), "filter update once the robot moved this far ...");
  f.number("update_angle", c.update_angle, "rad", at_least(0), "... or turned this much");
  f.flag("augmented", c.augmented, "random-sample injection (Gutmann & Fox 2002)");
  f.number("alpha_slow", c.alpha_slow, "1", open_interval(0, 1), "long-term average rate (< alpha_fast)");
  f.number("alpha_fast", c.alpha_fast, "1", open_closed(0, 1), "short-term average rate");
  f.number("max_injection", c.max_injection, "1", between(0, 1), "cap on the injected fraction per step");
  f.number("injection_ratio", c.injection_ratio, "1", open_closed(0, 1),
           "inject only while w_fast < injection_ratio w_slow");
  f.number("min_likelihood_ratio", c.min_likelihood_ratio, "1", any_value(),
           "w_fast below this fraction of w_slow counts as implausible (status)");
  f.number("takeover_updates", c.takeover_updates, "1", at_least(1),
           "updates in a row the recovery set must win before it replaces the tracked set");
  f.number("recovery_updates", c.recovery_updates, "1", at_least(1),
           "sensor updates the recovery set searches on after the last injection");
  f.number("displaced_updates", c.displaced_updates, "1", at_least(1),
           "sensor updates a displaced tracked set is kept after a takeover");
  f.section("motion_noise", c.motion_noise, "the motion noise's scales learnt from scan matches while localized");
  f.section("motion_noise_matcher", c.motion_noise_matcher, "the scan match at the estimate that motion_noise learns from");
  f.section("status", c.status, "when the estimate counts as localized or lost");
  f.number("seed", c.seed, "1", any_value(), "of every random draw");
}

/// Throws Error for values outside the ranges above.
void validate(const MclConfig& config);

/// KLD-sampling bound (Fox 2003, Eq. 10) for k bins; 1 for k <= 1.
std::size_t kld_particle_count(std::size_t k, double epsilon, double z);

class MonteCarloLocalization : public Localizer {
 public:
  /// The map must outlive the filter. Call one of the initialisers before update().
  MonteCarloLocalization(const LocalizationMap& map, const MclConfig& config = {});

  /// Particles drawn from a Gaussian around the pose (max(min_particles, 1000) of them).
  void initialize(const SE2& T_map_robot, const Covariance3& covariance);
  /// A global start: the first config.global.updates sensor updates score a grid of poses over
  /// the whole free space (GlobalPoseSearch), then max_particles are seeded around the best.
  void initialize_global();
  /// Whether the global start's coarse pass is still running.
  bool searching() const { return searching_; }
  /// Candidate places of a global start still tracked (0 once one place is left, and when tracking).
  std::size_t places() const { return place_log_likelihood_.size(); }
  /// The coarse pass of the last global start (null before initialize_global()).
  const GlobalPoseSearch* global_search() const { return search_.get(); }

  LocalizationEstimate update(const SE2& T_odom_robot, const LaserScan& scan) override;
  std::size_t sensor_updates() const override { return sensor_updates_; }
  std::string name() const override { return "mcl"; }
  const MotionNoiseLearner* motion_noise() const override { return &motion_noise_; }

  // The steps, for tests and benchmarks.
  void predict(const SE2& increment);  // the odometry's increment since the last update
  /// Weighs the particles by the scan; returns w_avg and updates w_slow, w_fast.
  double weigh(const ScanBeams& beams);
  /// The weighted mean and covariance of the particles (after weigh()).
  LocalizationEstimate summarize(const ScanBeams& beams);
  /// Low-variance resampling to the KLD count; seeds or refreshes the recovery set.
  void resample();

  const std::vector<SE2>& particles() const { return particles_; }
  const std::vector<double>& weights() const { return weights_; }
  double w_slow() const { return w_slow_; }
  double w_fast() const { return w_fast_; }
  /// Random poses added to the recovery set at the last resampling.
  std::size_t injected_last() const { return injected_last_; }
  /// The recovery hypotheses (empty while the tracked set explains the scans).
  const std::vector<SE2>& recovery_particles() const { return recovery_; }
  /// Times the recovery set replaced the tracked set.
  std::size_t takeovers() const { return takeovers_; }
  const MclConfig& config() const { return config_; }

 private:
  const LocalizationMap& map_;
  MclConfig config_;
  MotionNoiseLearner motion_noise_;
  Rng rng_;
  std::vector<SE2> particles_;
  std::vector<double> weights_;  // normalised after weigh()
  std::vector<SE2> scratch_;
  std::vector<double> log_likelihoods_;
  std::vector<SE2> recovery_;             // recovery hypotheses (see the header comment)
  std::vector<double> recovery_weights_;  // normalised after weigh()
  int recovery_wins_ = 0;                 // consecutive updates the recovery set won
  bool recovery_better_ = false;          // it explained the last scan better than the tracked set
  bool displaced_ = false;                // it is the tracked set a takeover displaced
  int updates_since_injection_ = 0;
  std::size_t takeovers_ = 0;

  struct SetLikelihood {
    double mean = 0.0;      // mean over the poses of the per-beam geometric mean likelihood
    double weighted = 0.0;  // the same, weighted by the normalised weights
    std::size_t best = 0;   // index of the most likely pose
  };
  /// Scores the poses by the scan into normalised weights.
  SetLikelihood weigh_poses(const ScanBeams& beams, const std::vector<SE2>& poses, std::vector<double>& weights);
  /// Scores the recovery set; swaps it in when it has won takeover_updates times in a row.
  void weigh_recovery(const ScanBeams& beams, const SetLikelihood& tracked);
  /// Seeds, refreshes or drops the recovery set by the injection probability.
  void update_recovery(double p_inject);
  void drop_recovery();
  /// A sensor update of the coarse pass; seeds the particles once it is done.
  LocalizationEstimate search_update(const SE2& T_odom_robot, const LaserScan& scan);
  /// Place evidence: sums each place's marginal likelihood, drops the places place_margin below
  /// the best, and sets the weights to the place posterior times the weights within each place.
  void weigh_places();
  bool places_decidable() const { return place_travel_ >= config_.place_min_travel; }
  /// Resamples each place to an equal share of max_particles; merges places that met; ends the
  /// place phase when one is left.
  void resample_places();
  std::unique_ptr<GlobalPoseSearch> search_;  // built by the first initialize_global()
  bool searching_ = false;                    // the coarse pass runs
  std::vector<std::uint32_t> place_of_;       // place of each particle while places are tracked
  std::vector<double> place_log_likelihood_;  // summed log marginal likelihood of each place
  std::vector<double> within_weights_;        // each particle's weight within its place
  int place_updates_ = 0;                     // sensor updates since the places were seeded
  double place_travel_ = 0.0;                 // m travelled since the places were seeded
  SE2 odom_at_start_;                         // odometry pose at the first scan
  bool averages_started_ = false;             // w_slow, w_fast hold a value
  bool initialized_ = false;
  bool started_ = false;          // the first scan has been used
  SE2 odom_at_update_;            // odometry pose at the last filter update
  LocalizationEstimate estimate_;  // at the last filter update
  LocalizationStatus status_;
  double w_slow_ = 0.0;
  double w_fast_ = 0.0;
  std::size_t injected_last_ = 0;
  std::size_t sensor_updates_ = 0;
};

/// Weighted mean (circular for theta) and covariance of poses; weights sum to 1.
void weighted_pose_statistics(const std::vector<SE2>& poses, const std::vector<double>& weights, SE2* mean,
                              Covariance3* covariance);

}  // namespace slam2d
