// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Hector SLAM: S. Kohlbrecher, O. von Stryk, J. Meyer, U. Klingauf, "A flexible and scalable SLAM
// system with full 3D motion estimation", SSRR 2011 (the 2D part, Sec. IV).
//
// For every scan: predict the pose (odometry delta, constant velocity or the last pose), optionally
// correct the sweep's rotational distortion and level the scan with an IMU attitude, match the
// end points against the map pyramid coarse to fine (registration/occupancy_gradient_match.hpp),
// and integrate the scan into every level when the pose moved more than a distance or angle
// threshold since the last map update. No loop closure: the map is built once, scan by scan; after a
// gap in the scans it searches that map for where it is (slam/relocalization/search_before_gap.hpp).
// Deterministic.

#include <array>
#include <optional>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/match_progress.hpp"
#include "slam2d/core/odometry_guard.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/grid/map_pyramid.hpp"
#include "slam2d/registration/match_fusion.hpp"
#include "slam2d/optim/robust_kernel.hpp"
#include "slam2d/registration/occupancy_gradient_match.hpp"
#include "slam2d/core/scan_gaps.hpp"
#include "slam2d/core/scan_preprocessing.hpp"
#include "slam2d/registration/correlative_map_match.hpp"
#include "slam2d/slam/relocalization/search_before_gap.hpp"

namespace slam2d {

enum class MotionPrior {
  kOdometry,          // last estimate * (odometry delta since the last scan) when the odometry
                      // guard trusts it, else HectorSlam::untrusted_starts; needs odometry poses
  kConstantVelocity,  // last estimate * (the last estimated motion, scaled to the time step)
  kLastPose,          // the last estimate (Hector's default without odometry)
};
constexpr auto choices(MotionPrior) {
  return std::array{Choice{"odometry", MotionPrior::kOdometry}, Choice{"constant_velocity", MotionPrior::kConstantVelocity},
                    Choice{"last_pose", MotionPrior::kLastPose}};
}

struct HectorSlamConfig {
  // The map pyramid: 3 levels from 5 cm; Hector's update factors p_hit 0.9 / p_miss 0.4. No-return
  // beams clear nothing (max_clear_range 0), as in Hector. Its grid.max_range is ignored: the map
  // takes max_range below, so matching and mapping use one usable range. A grazing wall's returns
  // mark no cells between them (grid.surface_hit_weight 0, an option, used only with the odometry
  // prior: without it the wall's dots are all that holds a corridor's open axis;
  // docs/methods/hector.md, "A grazing wall as a wall").
  MapPyramidConfig map{.levels = 3,
                       .grid = {.resolution = 0.05, .probability_hit = 0.9, .probability_miss = 0.4,
                                .probability_min = 0.12, .probability_max = 0.97, .max_clear_range = 0.0}};
  // A scan's open translation (a corridor with no depth edge in view) stays with the prediction
  // (matcher.scan_degeneracy_ratio 0.01, as the RBPF's proposal and graph SLAM's tracker; the map's
  // far dots of its grazing walls would pin the scan to the viewpoint that drew them). Scans of
  // the public logs, their ROS bags, the TurtleBot 4 bag and the office world never fall below it;
  // docs/methods/hector.md, "A corridor's open translation left to the odometry", has the
  // measurements and the cost (Intel with mixed pixels at every edge).
  HectorMatcherConfig matcher{.scan_degeneracy_ratio = 0.01};
  double min_range = 0.1;
  // Below the far readings some logs report for no-return; picked on ACES, checked on Intel and
  // FR079 with odometry (without odometry not robust: docs/defaults.md).
  double max_range = 25.0;  // > min_range
  double update_distance = 0.4;  // Hector's default
  double update_angle = 0.9;     // Hector's default
  MotionPrior prior = MotionPrior::kOdometry;
  double max_prior_dt = 1.0;
  double sweep_duration = 0.0;
  // A Gaussian prior on the translation at the odometry prediction added to the matching (not
  // in the paper), only where the odometry guard trusts the increment (never without odometry:
  // the last pose is no measurement). Without it, a small change of the input (1 cm of range
  // noise, where a stall falls) sends Hector's drift along ACES's and Intel's corridors anywhere
  // between 0.02 and 0.5 m (docs/methods/hector.md, "The odometry prior"). Sigma 3.2 cm at rest,
  // growing by 0.1 m per metre travelled (an odometry motion model's form; GMapping's srr), so a
  // log with a scan every few seconds gets a weaker prior per scan. The Cauchy kernel on its
  // Mahalanobis distance (scale 2 sigma) lets the scan win where the odometry is many sigmas off
  // (FR079's odometry counting a reverse as forward driving). No prior on the heading by default:
  // the scan fixes it, and odometry headings are what fail (wheel slip in turns). Picked on ACES
  // and Intel (stall phases, range-noise seeds); FR079, the odometry faults and a fast-turning
  // simulation held out (docs/defaults.md). Zero information disables a component. With
  // prior_from_motion_noise (graph SLAM's tracker's default) they hold only until a match has told
  // the noise.
  double prior_information_translation = 1000.0;
  double prior_information_rotation = 0.0;
  double prior_sigma_per_metre = 0.1;
  RobustKernel prior_kernel = kOdometryPriorKernel;
  // A catch-up's increment spans a freeze of seconds, which the per-scan sigma does not describe:
  // Intel with 3 s odometry gaps scores 0.16 m with the prior there, 0.027 m without (graph
  // SLAM's tracker keeps its weaker prior there: the sparse corrected logs need it).
  bool prior_at_catch_ups = false;
  // The prior weighed by the odometry's own uncertainty (not in the paper), in place of the three
  // constants above: the prediction's covariance, the last pose's plus the odometry increment's
  // motion noise (core/motion_fusion.hpp; its scale learnt online from how the matches agree with
  // the odometry, as for fuse_odometry below), brought into the matcher's units by the last
  // match's residual variance s^2 (the scan's own information is H / s^2, so the prior's in the
  // normal equations is s^2 P^-1). A good odometry so holds the match where the scan says little
  // (glass, a thin or noisy scan), a poor one lets the scan lead. The kernel above still applies.
  // On graph SLAM's tracker (with the Cauchy kernel) it holds ACES with three glass sectors at
  // 0.053 m against 1.00 m and lowers the noisy-laser and mixed-pixel errors on Intel and ACES
  // (docs/fusion_by_uncertainty.md, "The double count, measured"). Off for Hector: with the retry
  // below (recovery_residual 0.25) it keeps Freiburg campus's exact odometry (53.8 -> 4.2 m ATE),
  // Intel with its odometry out of step in time (0.8-1.7 -> 0.02-0.09 m) and FR079 at 1 Hz (0.40 ->
  // 0.044 m), but follows a drifting odometry where Hector has no loops to take it back (Intel's
  // 1 cm noise seeds up to 0.061 m, Edmonton degraded 0.27 -> 1.39 m ATE), and correcting the
  // drift loses ACES's loop: docs/fusion_by_uncertainty.md, "Hector weighing its odometry".
  bool prior_from_motion_noise = false;
  // Recovery (not in the paper): a match whose mean squared residual (1 - M)^2 exceeds this is
  // retried with a rotation search (a quarter turn either way from a trusted odometry increment's
  // prediction, every heading without one), kept when it fits a fifth better and, against a
  // trusted increment, explains the scan (matcher.rotation_search_min_explained). Off with odometry:
  // with the translation-only prior of constant weight it turns the robot round in ACES's
  // look-alike corridors (0.054 -> 1.66 m); graph SLAM's tracker, with the weighed prior, uses 0.25.
  double recovery_residual = 1.0;
  // Without odometry (prior != kOdometry) these replace the settings above and the matcher's:
  // the robot may have turned far between two scans (or during a gap in the log), and in round
  // halls near-equal costs must not pull the heading away from the guess. The search range was
  // picked on Intel, ACES and FR079, the margin and the residual on ACES; none is yet checked
  // on a held-out log (docs/defaults.md).
  double rotation_search_without_odometry = 0.4;
  double rotation_margin_without_odometry = 0.1;
  double recovery_residual_without_odometry = 0.25;
  // With the odometry prior, each increment is checked first (core/odometry_guard.hpp): a scan
  // whose increment is not trusted (a stall, its catch-up, a jump) is matched as without
  // odometry (the settings above, no prior, no solution remapping) from two starts, and the
  // better fit is kept (HectorSlam::untrusted_starts). A standing increment within a burst of
  // scans is confirmed against the last motion repeated (confirm_burst 5, the guard's 0: off;
  // HectorSlam::confirming_start).
  OdometryGuardConfig odometry_guard{.confirm_burst = 5.0};
  // Fusion by uncertainty (core/motion_fusion.hpp; not in the paper): where the odometry is
  // trusted, the match is one measurement of the pose and the prediction another, a Kalman
  // filter's: the last pose's covariance plus the odometry's motion noise (its scale learnt from
  // the matches), against the match's covariance (the Gauss-Newton Hessian's, floored and inflated
  // along a degenerate direction: registration/match_fusion.hpp). Consistent, they are averaged by
  // their information; disagreeing beyond the gate, the better-conditioned one stands alone. A
  // scan that carries little (noise, glass, a corridor) so leaves the step to the odometry.
  // Off by default: see docs/methods/hector.md, "Fusion by uncertainty".
  bool fuse_odometry = false;
  OdometryNoiseConfig odometry_noise{};
  // The odometry's systematic error (a scale of distance, of turn, a heading drift per metre:
  // core/motion_fusion.hpp's OdometryCalibration) learnt from the matches over stretches of half a
  // metre, and each trusted increment corrected before it predicts (the stretches:
  // core/motion_fusion.hpp's CalibrationStretches, as the RBPF's), under any odometry prior (until
  // 2026-12-07 only with the weighed prior or the fusion; under the constant one the stretches are
  // weighed by the noise model unscaled). The noise model describes noise; without this a wheel
  // odometry that turns the same way every metre (Intel's, 0.06 rad/m) pulls the match along its
  // drift. On in graph SLAM's tracker (graph_slam.cpp's default_tracking_config: 1000 stretches,
  // significance 5; docs/fusion_by_uncertainty.md, "Only what stands out"). Off in Hector: with
  // its weighed prior and retry, over 100 stretches it mends Edmonton's degraded odometry (1.39 ->
  // 0.64 m ATE) but loses ACES's loop (0.045 -> 0.097 m, with a 198 s gap 0.15 m), over 1000
  // FHW's (0.20 -> 2.79 m): docs/fusion_by_uncertainty.md, "Hector weighing its odometry"; under
  // its constant prior, with the open axis, it holds the hospital world but loses Intel under a
  // noisy laser: docs/methods/hector.md, "The odometry's systematic error under Hector's own prior".
  OdometryCalibrationConfig odometry_calibration{.window = 0.0};
  MatchNoiseConfig match_noise{.floor_translation = 0.0, .floor_rotation = 0.0};
  double fusion_gate = kMotionGateChi2;
  // After a gap in the scans a new map from the prediction, and the map before the gap searched
  // for where it is (slam/relocalization/search_before_gap.hpp; docs/methods/hector.md, "Across a
  // gap in the scans"). Graph SLAM's tracker ignores it: graph SLAM restarts it, its loop closer searches.
  GapRelocalizationConfig relocalization{};
};

template <typename Fields>
void describe(Fields& f, HectorSlamConfig& c) {
  f.section("map", c.map, "the map pyramid (its grid.max_range is replaced by max_range)");
  f.section("matcher", c.matcher, "the scan-to-map matcher");
  f.number("min_range", c.min_range, "m", at_least(0), "shorter readings are dropped (robot body, dust)");
  f.number("max_range", c.max_range, "m", greater_than(0),
           "usable range for matching and mapping (> min_range); longer readings are no-return");
  f.number("update_distance", c.update_distance, "m", at_least(0), "map update when the pose moved more than this since the last one ...");
  f.number("update_angle", c.update_angle, "rad", at_least(0), "... or turned more than this");
  f.choice("prior", c.prior, "the matcher's initial guess");
  f.number("max_prior_dt", c.max_prior_dt, "s", at_least(0),
           "constant velocity is not extrapolated over longer gaps (last pose instead)");
  f.number("sweep_duration", c.sweep_duration, "s", at_least(0),
           "first to last beam; > 0 enables the rotational distortion correction");
  f.number("prior_information_translation", c.prior_information_translation, "1/m^2", at_least(0),
           "information of the odometry prior on the translation at rest (0: off)");
  f.number("prior_information_rotation", c.prior_information_rotation, "1/rad^2", at_least(0),
           "information of the odometry prior on the heading (0: off)");
  f.number("prior_sigma_per_metre", c.prior_sigma_per_metre, "m per m travelled", at_least(0),
           "growth of the prior's translation sigma");
  f.section("prior_kernel", c.prior_kernel, "on the prior's Mahalanobis distance");
  f.flag("prior_at_catch_ups", c.prior_at_catch_ups, "keep the prior on a catch-up's increment");
  f.flag("prior_from_motion_noise", c.prior_from_motion_noise,
         "the prior's information from the prediction's covariance (the learnt motion noise), not the constants above");
  f.number("recovery_residual", c.recovery_residual, "1", at_least(0),
           "a match with a larger mean squared residual is retried with a rotation search; 1 never triggers");
  f.number("rotation_search_without_odometry", c.rotation_search_without_odometry, "rad", at_least(0),
           "matcher.rotation_search_range without odometry");
  f.number("rotation_margin_without_odometry", c.rotation_margin_without_odometry, "1", closed_open(0, 1),
           "matcher.rotation_search_margin without odometry");
  f.number("recovery_residual_without_odometry", c.recovery_residual_without_odometry, "1", at_least(0),
           "recovery_residual without odometry");
  f.section("odometry_guard", c.odometry_guard, "the check of each odometry increment");
  f.flag("fuse_odometry", c.fuse_odometry, "fuse each match with the odometry's prediction by their covariances");
  f.section("odometry_noise", c.odometry_noise, "the odometry's motion noise model (core/motion_fusion.hpp)");
  f.section("odometry_calibration", c.odometry_calibration,
            "the odometry's systematic error learnt from the matches and corrected before it predicts (window 0: off)");
  f.section("match_noise", c.match_noise, "the match's covariance for the fusion (registration/match_fusion.hpp)");
  f.number("fusion_gate", c.fusion_gate, "1", greater_than(0),
           "chi-square (3 dof) beyond which prediction and match disagree and the better-conditioned one wins");
  f.section("relocalization", c.relocalization, "after a gap in the scans, the search of the map before it");
}

/// Extra inputs of one scan.
struct HectorInputs {
  std::optional<SE2> T_odom_robot{};    // the odometry pose at the scan (kOdometry prior, angular rate)
  std::optional<Attitude> attitude{};   // IMU roll/pitch: the end points are levelled before matching
  std::optional<double> angular_rate{}; // rad/s, IMU yaw rate for the distortion correction
};

struct HectorStep {
  SE2 T_map_robot;
  Covariance3 covariance = Covariance3::Zero();  // from the Gauss-Newton Hessian; zero on the first scan
  SE2 prediction;                                // the matcher's initial guess
  MatchResult match;                       // empty on the first scan
  bool matched = false;                          // false on the first scan (no map yet)
  bool map_updated = false;
  OdometryCheck odometry;                        // the guard's verdict (kOdometry prior only)
};


/// Throws Error for negative or non-finite ranges/thresholds, min_range >= max_range, or an invalid
/// map or matcher configuration.
void validate(const HectorSlamConfig& config);

class HectorSlam {
 public:
  explicit HectorSlam(const HectorSlamConfig& config = {});

  /// Processes one scan. Throws Error when config.prior is kOdometry and no odometry pose is given.
  HectorStep add_scan(const LaserScan& scan, const HectorInputs& inputs = {});
  /// Starts a new map: the next scan is placed at its prediction and not matched, as the first
  /// one was, and the maps after it hold only the scans from there (graph SLAM's tracker after a
  /// gap in the scans, where the prediction may be far off and the old map would pull the new
  /// scans onto the wrong place). The pose, the odometry's state and the learnt noise go on.
  void restart_map();

  const MapPyramid& map() const { return map_; }
  /// The map to write: the finest level, over the maps set aside at gaps after which Hector did not
  /// find its place (or is still searching for it), each in the odometry's frame across its gap.
  OccupancyMap occupancy_map() const;
  const GapStats& gap_stats() const { return gap_stats_; }
  /// One pose per scan added, in order, stamped with the scan's stamp.
  const Trajectory& trajectory() const { return trajectory_; }
  std::size_t map_updates() const { return map_updates_; }
  /// Scans whose matched motion since the last map update the odometry refuted (it then carries
  /// the stretch: core/match_progress.hpp).
  std::size_t stuck_matches() const { return stuck_matches_; }
  const HectorSlamConfig& config() const { return config_; }
  const OdometryGuardStats& odometry_stats() const { return odometry_guard_.stats(); }
  const MotionFusionStats& fusion_stats() const { return fusion_stats_; }
  const OdometryNoiseModel& odometry_noise() const { return odometry_noise_; }
  const OdometryCalibration& odometry_calibration() const { return odometry_calibration_; }
  /// The odometry's systematic error is learnt and corrected (config.odometry_calibration).
  bool calibrating() const {
    return config_.odometry_calibration.window > 0.0;
  }

 private:
  struct ScanMatch {
    MatchResult result;
    bool refuted = false;  // an increment to be confirmed lost to the competing start (confirming_start)
  };
  struct ConfirmingStart {
    SE2 pose;
    std::optional<PosePrior> prior;
  };
  std::optional<ConfirmingStart> confirming_start(const SE2& prediction) const;
  ScanMatch match(const LaserScan& corrected, const HectorInputs& inputs, const SE2& prediction) const;
  struct UntrustedStarts {
    SE2 first;                   // the prediction
    std::optional<SE2> second;   // the competing start, if any (kCompetingStartAdvantage)
  };
  MatchResult match_from(const std::vector<Eigen::Vector2d>& points, const SE2& start, bool with_odometry,
                               const std::optional<PosePrior>& prior) const;
  std::optional<UntrustedStarts> untrusted_starts() const;
  double recovery_residual(bool with_odometry) const;
  std::optional<PosePrior> pose_prior(const SE2& prediction) const;
  bool odometry_trusted() const;
  SE2 predict(const LaserScan& scan) const;
  double angular_rate(const LaserScan& scan, const HectorInputs& inputs, const SE2& prediction) const;
  void fuse(HectorStep& step);
  Covariance3 predicted_covariance() const;
  SE2 odometry_increment() const;
  bool odometry_refutes_matches(const SE2& T_map_robot) const;
  bool needs_map_update(const SE2& T_map_robot) const;
  void integrate(const LaserScan& scan, const HectorInputs& inputs, const SE2& T_map_robot);
  void begin_relocalization(double gap);
  void relocalize(const LaserScan& corrected, const HectorInputs& inputs);
  void relocalize_at(const SE2& T_before_new);
  void abandon_relocalization();
  void remember(double stamp, const HectorInputs& inputs);

  HectorSlamConfig config_;
  HectorMatcherConfig free_matcher_;  // the matcher's settings without (trusted) odometry
  double free_recovery_residual_ = 0.0;
  OdometryGuard odometry_guard_;
  OdometryCheck odometry_;             // the guard's verdict on this scan's odometry
  MapPyramid map_;
  bool map_empty_ = true;              // no scan in map_ yet (the first scan, or after restart_map)
  Trajectory trajectory_;
  std::optional<SE2> last_pose_;       // estimate at the previous scan
  SE2 last_moved_pose_;                // estimate at the last scan whose odometry pose moved
  std::optional<SE2> previous_pose_;   // estimate at the scan before that
  double last_stamp_ = 0.0;
  double previous_dt_ = 0.0;           // s, between the two previous scans
  SE2 last_update_pose_;
  std::size_t map_updates_ = 0;
  MatchProgress progress_;  // the guarded odometry since the last map update
  std::size_t stuck_matches_ = 0;
  OdometryNoiseModel odometry_noise_;
  OdometryCalibration odometry_calibration_;          // calibrating()
  CalibrationStretches calibration_stretches_;
  MotionFusionStats fusion_stats_;
  Covariance3 last_covariance_ = Covariance3::Zero();  // of last_pose_ in the map (the first scan's: zero)
  double residual_variance_ = 0.0;                      // the last match's mean squared residual (0: none yet)
  // Across gaps in the scans (relocalization.enabled).
  struct Relocalization {  // after a gap, while the map before it is searched
    MapPyramid before;      // the map before the gap
    SearchBeforeGap search;
    std::size_t first_scan = 0;  // the trajectory's index of the first scan after the gap
    std::vector<std::pair<LaserScan, SE2>> mapped{};  // the scans in the new map, at their poses there
  };
  ScanGapDetector gaps_;
  std::vector<OdometryAndEstimate> history_;  // since the last gap, with odometry: its drift's measure
  std::optional<Relocalization> relocalization_;
  std::vector<OccupancyMap> earlier_maps_;   // set aside at gaps not relocalized, the oldest first
  GapStats gap_stats_;
};

}  // namespace slam2d
