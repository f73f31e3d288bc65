// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/hector/hector_slam.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry.hpp"
#include "slam2d/registration/free_space_check.hpp"

namespace slam2d {

namespace {

// A mean squared residual (1 - M)^2 never exceeds 1: no match is retried.
constexpr double kNoRecovery = 1.0;

// How far the retry after a poor fit turns from the guess: every heading without a trusted
// odometry increment; a quarter turn either way with one. A trusted increment's heading may be
// off by much (an odometry out of step in time in a turn: up to 1.2 rad on Intel shifted by
// 0.3-0.6 s), but a wheel odometry that turned the robot around unnoticed is a jump, which the
// guard does not trust. Beyond a quarter turn a retry with a trusted increment only ever found
// the mirror heading of a symmetric place (Intel shifted by 0.6 s: a corridor's scan fit 28 %
// better turned around, 0.92 m over all relations against 0.072 m).
constexpr double kRetryRangeWithOdometry = std::numbers::pi / 2.0;

// The scan with each reading scaled to its horizontal length under the attitude (bearings kept:
// their change is second order in roll and pitch), for the map update of a tilted scan.
LaserScan levelled_scan(const LaserScan& scan, const Attitude& attitude) {
  LaserScan levelled = scan;
  const double theta = scan.T_robot_sensor.theta();
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double a = theta + scan.angle(i);
    const auto projected = project_to_horizontal({Eigen::Vector2d(std::cos(a), std::sin(a))}, attitude);
    levelled.ranges[i] = scan.ranges[i] * projected.front().norm();
  }
  return levelled;
}

// The pyramid's settings with the usable range of the whole system.
MapPyramidConfig map_config(const HectorSlamConfig& config) {
  MapPyramidConfig map = config.map;
  map.grid.max_range = config.max_range;
  // Without the odometry prior nothing else holds a corridor's open axis: its walls stay dots.
  if (config.prior != MotionPrior::kOdometry) map.grid.surface_hit_weight = 0.0;
  return map;
}

}  // namespace

void validate(const HectorSlamConfig& config) {
  check_fields(config, "HectorSlamConfig");
  check(config.max_range > config.min_range, "HectorSlamConfig: max_range must be > min_range");
  validate(config.matcher);
  validate(config.odometry_noise);
  validate(config.relocalization);
}

HectorSlam::HectorSlam(const HectorSlamConfig& config)
    : config_(config),
      odometry_guard_(config.odometry_guard),
      map_(map_config(config)),
      odometry_noise_(config.odometry_noise),
      odometry_calibration_(config.odometry_calibration),
      gaps_(config.relocalization.gap) {
  validate(config_);
  free_matcher_ = config_.matcher;
  free_matcher_.rotation_search_range = config_.rotation_search_without_odometry;
  free_matcher_.rotation_search_margin = config_.rotation_margin_without_odometry;
  free_matcher_.degeneracy_ratio = 0.0;  // the directions a scan leaves open have no measurement to stay at
  free_matcher_.scan_degeneracy_ratio = 0.0;  // nor a scan's open translation
  free_recovery_residual_ = config_.recovery_residual_without_odometry;
  validate(free_matcher_);
}

// The odometry prior is in force and this scan is predicted by the odometry: its increment is
// trusted, or it is a catch-up applied from the scan where the odometry last moved.
bool HectorSlam::odometry_trusted() const {
  return config_.prior == MotionPrior::kOdometry && (odometry_.trusted() || odometry_.fault == OdometryFault::kCatchUp);
}

HectorStep HectorSlam::add_scan(const LaserScan& scan, const HectorInputs& inputs) {
  check(config_.prior != MotionPrior::kOdometry || inputs.T_odom_robot.has_value(),
        "HectorSlam: the odometry prior needs an odometry pose with every scan");
  HectorStep step;
  if (config_.prior == MotionPrior::kOdometry) odometry_ = odometry_guard_.check(scan.stamp, *inputs.T_odom_robot);
  step.odometry = odometry_;
  const double gap = config_.relocalization.enabled ? gaps_.gap_before(scan.stamp) : 0.0;
  if (gap > 0.0) begin_relocalization(gap);
  step.prediction = predict(scan);
  step.T_map_robot = step.prediction;
  LaserScan corrected = scan;
  if (config_.sweep_duration > 0.0) {
    corrected = correct_rotational_distortion(scan, angular_rate(scan, inputs, step.prediction), config_.sweep_duration);
  }
  if (last_pose_ && !map_empty_) {  // Sec. IV-B/C: match against the map built so far
    ScanMatch matched = match(corrected, inputs, step.prediction);
    step.match = std::move(matched.result);
    odometry_.refuted = matched.refuted;
    if (odometry_.refuted) odometry_guard_.count_refutation(odometry_);
    step.odometry = odometry_;
    step.matched = true;
    step.T_map_robot = step.match.T_target_source;
    step.covariance = step.match.covariance;
    fuse(step);
  }
  if (config_.prior == MotionPrior::kOdometry) progress_.add(odometry_increment(), odometry_.trusted() && !odometry_.refuted);
  if (step.matched && odometry_refutes_matches(step.T_map_robot)) {
    step.T_map_robot = last_update_pose_ * progress_.odometry();  // the odometry carries the stretch
    step.covariance = predicted_covariance();
    ++stuck_matches_;
  }
  if (map_empty_ || (!odometry_.hold_map && needs_map_update(step.T_map_robot))) {
    integrate(corrected, inputs, step.T_map_robot);
    step.map_updated = true;
  }
  if (last_pose_) last_covariance_ = step.covariance;
  previous_dt_ = last_pose_ ? scan.stamp - last_stamp_ : 0.0;
  previous_pose_ = last_pose_;
  last_pose_ = step.T_map_robot;
  if (odometry_.moved) last_moved_pose_ = step.T_map_robot;
  last_stamp_ = scan.stamp;
  trajectory_.push_back(scan.stamp, step.T_map_robot);
  if (config_.relocalization.enabled) remember(scan.stamp, inputs);
  if (relocalization_) {
    relocalize(corrected, inputs);
    step.T_map_robot = *last_pose_;
  }
  return step;
}

// Whether the odometry since the last map update refutes the matched motion to `T_map_robot`
// (core/match_progress.hpp), by the odometry noise model's sigma before any learning: the map
// grows only when the matched motion reaches update_distance, so a match held back would hold the
// map (the hospital world with mixed pixels, phantoms 23 m ahead: the robot stood still in the map
// for 40 s on the second lap; 13.0 -> 1.57 m ATE).
bool HectorSlam::odometry_refutes_matches(const SE2& T_map_robot) const {
  if (config_.prior != MotionPrior::kOdometry || map_empty_) return false;
  const double sigma = odometry_noise_.sigma_translation(progress_.odometry());
  return progress_.refutes(last_update_pose_.between(T_map_robot), config_.update_distance, sigma);
}

void HectorSlam::restart_map() {
  map_ = MapPyramid(map_config(config_));
  map_empty_ = true;
}

// The match and the odometry's prediction as two measurements of the pose (the header's fusion):
// the prediction's covariance is the last pose's plus the motion noise of the trusted increment
// (in the map frame); the match's, registration/match_fusion.hpp's. Without a trusted increment
// (no odometry, a stall, a catch-up, a jump, one the scans refuted) the match stands, with its
// floored covariance.
void HectorSlam::fuse(HectorStep& step) {
  const MotionMeasurement match = match_measurement(step.match, config_.match_noise);
  const bool known = match.covariance.diagonal().maxCoeff() < kUnknownVariance;
  if (known) step.covariance = match.covariance;
  residual_variance_ = step.match.residual * step.match.residual;
  // A trusted increment and a match that knows its pose: a measurement of the odometry's motion,
  // for its systematic error under any prior (the stretches' weights from the noise model, learnt
  // or not) and for its noise where that is learnt.
  const bool usable = config_.prior == MotionPrior::kOdometry && odometry_.trusted() && known;
  if (calibrating()) {
    calibration_stretches_.add(usable, odometry_.increment, odometry_noise_.covariance(odometry_.increment), match.value,
                               match.covariance, odometry_calibration_);
  }
  if (!usable || !(config_.fuse_odometry || config_.prior_from_motion_noise)) return;
  const Covariance3 predicted = predicted_covariance();
  // The odometry's noise is learnt from the match's motion since the last pose, whose uncertainty
  // is the two poses' (the last one's already counted in the prediction); what the calibration
  // corrects is not noise.
  odometry_noise_.observe(odometry_increment(), last_pose_->between(match.value),
                          rotate_covariance(last_covariance_ + match.covariance, -last_pose_->theta()));
  if (!config_.fuse_odometry) return;
  const FusedMotion fused =
      fuse_motion({step.prediction, predicted}, match, config_.fusion_gate);
  fusion_stats_.count(fused.outcome);
  step.T_map_robot = fused.value;
  step.covariance = fused.covariance;
}

HectorSlam::ScanMatch HectorSlam::match(const LaserScan& corrected, const HectorInputs& inputs, const SE2& prediction) const {
  std::vector<Eigen::Vector2d> points = usable_end_points(corrected, config_.min_range, config_.max_range);
  if (inputs.attitude) points = project_to_horizontal(points, *inputs.attitude);
  const bool with_odometry = odometry_trusted();
  ScanMatch matched{match_from(points, prediction, with_odometry, with_odometry ? pose_prior(prediction) : std::nullopt)};
  MatchResult& result = matched.result;
  if (const std::optional<UntrustedStarts> starts = untrusted_starts(); starts && starts->second) {
    MatchResult second = match_from(points, *starts->second, false, std::nullopt);
    if (second.cost < kCompetingStartAdvantage * result.cost) result = std::move(second);
  } else if (const std::optional<ConfirmingStart> start = confirming_start(prediction)) {
    MatchResult second = match_scan_to_pyramid(map_, points, start->pose, config_.matcher, start->prior);
    const OccupancyGrid& finest = map_.level(0);
    matched.refuted = second.cost < kCompetingStartAdvantage * result.cost &&
                      explained_share(finest, points, second.T_target_source) > explained_share(finest, points, result.T_target_source);
    if (matched.refuted) result = std::move(second);  // then the match stands alone (fuse)
  }
  return matched;
}

// The start that competes with a trusted increment the guard asks the scans to confirm; it wins
// with a fit a fifth better (kCompetingStartAdvantage) that also explains more of the scan:
//  - over a pause (OdometryCheck::confirm): the last pose, matched as the prediction is, with its
//    prior (so the two costs compare), without the retry over every heading: a retry from there
//    found 1.4 rad where ACES's odometry lagged after its 3 s gap (Hector 1.71 m over all
//    relations). Without the prior the last pose's fit slid 0.18 m along ACES's corridor with
//    three glass sectors (graph 0.043 -> 0.19 m);
//  - within a burst (OdometryCheck::burst), where the odometry stood: the last estimated motion
//    repeated, without a prior (the prior would hold it at the standing odometry). The scans of
//    Intel's bursts, read 1 ms apart after a pause, were taken during it, a rhythm's step apart,
//    and the robot turned between them while the odometry, logged at its own rate, stood. Also
//    where the last motion was about nil: then the start is the prediction's, and only the prior
//    differs (Intel with the odometry +0.3 / +0.6 / -0.3 / -0.6 s out of step, Hector over all
//    relations: 0.029 / 0.027 / 0.037 / 0.029 m, and 0.041 / 0.036 / 0.051 / 0.073 with no
//    start where the last motion was within moving_translation and moving_rotation).
std::optional<HectorSlam::ConfirmingStart> HectorSlam::confirming_start(const SE2& prediction) const {
  if (config_.prior != MotionPrior::kOdometry || !last_pose_) return std::nullopt;
  if (odometry_.confirm) return ConfirmingStart{*last_pose_, pose_prior(prediction)};
  if (!odometry_.burst || !previous_pose_) return std::nullopt;
  return ConfirmingStart{*last_pose_ * previous_pose_->between(*last_pose_), std::nullopt};
}

// Gauss-Newton on the pyramid from `start`, with the odometry settings or those without, and
// the retry over the headings around it after a poor fit (e.g. the robot turned during a gap in
// the log; kRetryRangeWithOdometry).
// The retry must fit a fifth better to win (kCompetingStartAdvantage): a poor fit can also mean a
// scan the map cannot explain (a passer-by, a door, a burst of bad readings) at the right pose,
// and among every heading one fits a little better by chance. Taking it would turn the tracker
// far and back a few scans later, a jump that anything downstream reads as motion.
MatchResult HectorSlam::match_from(const std::vector<Eigen::Vector2d>& points, const SE2& start,
                                         bool with_odometry, const std::optional<PosePrior>& prior) const {
  const HectorMatcherConfig& matcher = with_odometry ? config_.matcher : free_matcher_;
  MatchResult result = match_scan_to_pyramid(map_, points, start, matcher, prior);
  if (mean_squared_residual(result) > recovery_residual(with_odometry)) {
    HectorMatcherConfig wide = matcher;
    wide.rotation_search_range = with_odometry ? kRetryRangeWithOdometry : std::numbers::pi;
    // A heading the odometry lost: kCompetingStartAdvantage judges it; against the prior of a
    // trusted increment the turned fit must also explain the scan, as any rotated start must
    // (may_overrule; without odometry there is no prior and no such test).
    MatchResult retry = match_scan_to_pyramid(map_, points, start, wide, prior);
    if (retry.cost < kCompetingStartAdvantage * result.cost) result = std::move(retry);
  }
  return result;
}

// The fit worse than which a match is retried over every heading: the robot may have turned far
// without odometry, across a jump or where the odometry slipped in a turn, but not within a stall,
// where the map is held (OdometryCheck::hold_map) and a poor fit is the robot moving on unseen: a
// retry there turned graph SLAM around in ACES's corridors (10 s stalls: 2.46 m against 0.052).
double HectorSlam::recovery_residual(bool with_odometry) const {
  const bool stalled = odometry_.fault == OdometryFault::kStall || odometry_.fault == OdometryFault::kCatchUp;
  if (config_.prior == MotionPrior::kOdometry && stalled) return kNoRecovery;
  return with_odometry ? config_.recovery_residual : free_recovery_residual_;
}

// Where the match of a scan whose odometry increment the guard did not trust starts, and the
// second start that competes with it:
//  - stall, its first scan: the last estimated motion repeated (a stall is declared only after
//    the pose stood still for a while, so that motion is what the scans showed meanwhile: about
//    none for a robot come to rest, a metre in a log with a scan every two seconds), against the
//    last pose; its later scans: the last pose alone (repeating the motion scan after scan would
//    carry on a turn the scans cannot refute: Intel, 1 rad over a burst of scans 1 ms apart);
//  - catch-up: the estimate at the scan where the odometry last moved, moved by the catch-up,
//    which carries the motion since then, so nothing is counted twice; against the last pose;
//  - jump: the last pose alone. The odometry competed here once, for a motion the bounds did not
//    foresee; an odometry that restarted from its origin 21.5 m away then won in ACES's look-alike
//    corridors (graph SLAM 2.42 m with `odom-reset:every=120`, 0.0371 m without it).
// The second start wins with a fit a fifth better (kCompetingStartAdvantage).
std::optional<HectorSlam::UntrustedStarts> HectorSlam::untrusted_starts() const {
  if (config_.prior != MotionPrior::kOdometry || !last_pose_ || odometry_.trusted()) return std::nullopt;
  switch (odometry_.fault) {
    case OdometryFault::kStall: {
      if (!odometry_.stall_start || !previous_pose_) return UntrustedStarts{*last_pose_, std::nullopt};
      return UntrustedStarts{*last_pose_ * previous_pose_->between(*last_pose_), *last_pose_};
    }
    case OdometryFault::kCatchUp: return UntrustedStarts{last_moved_pose_ * odometry_.increment, *last_pose_};
    case OdometryFault::kJump: return UntrustedStarts{*last_pose_, std::nullopt};
    case OdometryFault::kNone: break;
  }
  return std::nullopt;
}

// The odometry prediction's covariance in the map: the last pose's plus the motion noise of this
// scan's increment (the learnt model's), turned into the map frame.
Covariance3 HectorSlam::predicted_covariance() const {
  return last_covariance_ + rotate_covariance(odometry_noise_.covariance(odometry_increment()), last_pose_->theta());
}

// This scan's odometry increment, corrected for the systematic error learnt so far where it is
// trusted and calibrating().
SE2 HectorSlam::odometry_increment() const {
  return calibrating() && odometry_.trusted() ? odometry_calibration_.corrected(odometry_.increment) : odometry_.increment;
}

// The Gaussian prior at the odometry prediction; none without odometry or where the guard did not
// trust this scan's increment, and at a catch-up only if config.prior_at_catch_ups.
std::optional<PosePrior> HectorSlam::pose_prior(const SE2& prediction) const {
  if (config_.prior_information_translation <= 0.0 && config_.prior_information_rotation <= 0.0) return std::nullopt;
  if (!odometry_trusted() || (odometry_.fault == OdometryFault::kCatchUp && !config_.prior_at_catch_ups)) return std::nullopt;
  if (config_.prior_from_motion_noise && last_pose_ && residual_variance_ > 0.0) {  // s^2 P^-1 (config)
    return PosePrior{.mean = prediction, .information = residual_variance_ * information_from_covariance(predicted_covariance()),
                     .kernel = config_.prior_kernel};
  }
  // Translation information 1 / (sigma at rest + growth * distance travelled)^2.
  double translation = config_.prior_information_translation;
  if (translation > 0.0) {
    const double sigma = 1.0 / std::sqrt(translation) + config_.prior_sigma_per_metre * odometry_.increment.translation().norm();
    translation = 1.0 / (sigma * sigma);
  }
  const Eigen::Vector3d information(translation, translation, config_.prior_information_rotation);
  return PosePrior{.mean = prediction, .information = information.asDiagonal(), .kernel = config_.prior_kernel};
}

SE2 HectorSlam::predict(const LaserScan& scan) const {
  if (!last_pose_) return SE2::identity();
  switch (config_.prior) {
    case MotionPrior::kOdometry:
      if (odometry_.trusted()) return *last_pose_ * odometry_increment();
      return untrusted_starts()->first;
    case MotionPrior::kConstantVelocity: {
      const double dt = scan.stamp - last_stamp_;
      if (!previous_pose_ || dt > config_.max_prior_dt) return *last_pose_;
      return *last_pose_ * constant_velocity_motion(previous_pose_->between(*last_pose_), dt, previous_dt_);
    }
    case MotionPrior::kLastPose: break;
  }
  return *last_pose_;
}

// rad/s: the IMU's rate if given, else the predicted rotation since the last scan over its time step.
double HectorSlam::angular_rate(const LaserScan& scan, const HectorInputs& inputs, const SE2& prediction) const {
  if (inputs.angular_rate) return *inputs.angular_rate;
  const double dt = scan.stamp - last_stamp_;
  if (!last_pose_ || dt <= 0.0 || dt > config_.max_prior_dt) return 0.0;
  return angle_difference(prediction.theta(), last_pose_->theta()) / dt;
}

bool HectorSlam::needs_map_update(const SE2& T_map_robot) const {
  const SE2 motion = last_update_pose_.between(T_map_robot);
  return motion.translation().norm() > config_.update_distance || std::abs(motion.theta()) > config_.update_angle;
}

void HectorSlam::integrate(const LaserScan& scan, const HectorInputs& inputs, const SE2& T_map_robot) {
  LaserScan usable = inputs.attitude ? levelled_scan(scan, *inputs.attitude) : scan;
  usable.range_min = std::max(usable.range_min, config_.min_range);
  map_.integrate_scan(usable, T_map_robot);
  if (relocalization_) relocalization_->mapped.emplace_back(std::move(usable), T_map_robot);
  map_empty_ = false;
  last_update_pose_ = T_map_robot;
  progress_.restart();
  ++map_updates_;
}

// The odometry's pose and Hector's at this scan, every half second (the drift over a gap is
// measured on stretches of ten seconds and more).
void HectorSlam::remember(double stamp, const HectorInputs& inputs) {
  if (config_.prior != MotionPrior::kOdometry || !inputs.T_odom_robot) return;
  add_to_history(history_, {stamp, *inputs.T_odom_robot, *last_pose_});
}

// A gap in the scans ended: the map so far is set aside to be searched, with a window of the
// odometry's drift over the gap (config), and a new map starts at the prediction. A gap while the
// map before an earlier one is still searched for gives that search up: the map since then is
// the one to find the robot in now.
void HectorSlam::begin_relocalization(double gap) {
  ++gap_stats_.gaps;
  if (relocalization_) abandon_relocalization();
  if (map_empty_) return;
  const GapRelocalizationConfig& c = config_.relocalization;
  const Drift drift = odometry_drift_over(history_, gap);
  if (within_tracker_reach(c.gap, c.sigmas * drift.translation, c.sigmas * drift.rotation)) {
    ++gap_stats_.tracked;  // an odometry this good: the tracker's own match reaches the place
    return;
  }
  history_.clear();
  SearchBeforeGap search(c, map_.level(0), drift);
  relocalization_.emplace(Relocalization{.before = std::move(map_), .search = std::move(search), .first_scan = trajectory_.size()});
  restart_map();
}

// One more scan after the gap searched for in the map before it (SearchBeforeGap); after
// max_attempts, or max_mapped_scans in the new map, Hector goes on in the new map.
void HectorSlam::relocalize(const LaserScan& corrected, const HectorInputs& inputs) {
  Relocalization& r = *relocalization_;
  if (r.mapped.size() >= static_cast<std::size_t>(config_.relocalization.max_mapped_scans)) {
    abandon_relocalization();
    return;
  }
  std::vector<Eigen::Vector2d> points = usable_end_points(corrected, config_.min_range, config_.max_range);
  if (inputs.attitude) points = project_to_horizontal(points, *inputs.attitude);
  const int attempts = r.search.attempts();
  const SearchBeforeGap::Verdict verdict = r.search.add(points, *last_pose_, [&] { return wall_points(map_.level(0)); });
  gap_stats_.attempts += static_cast<std::size_t>(r.search.attempts() - attempts);
  if (verdict.T_before_new) {
    relocalize_at(*verdict.T_before_new);
  } else if (verdict.give_up) {
    abandon_relocalization();
  }
}

// The new map's scans go into the map before the gap at their poses moved by T_before_new, which
// becomes the map; every pose since the gap moves with them.
void HectorSlam::relocalize_at(const SE2& T_before_new) {
  Relocalization& r = *relocalization_;
  for (const auto& [scan, pose] : r.mapped) r.before.integrate_scan(scan, T_before_new * pose);
  map_ = std::move(r.before);
  map_empty_ = false;
  std::vector<StampedPose> poses = trajectory_.poses();
  for (std::size_t i = r.first_scan; i < poses.size(); ++i) poses[i].pose = T_before_new * poses[i].pose;
  trajectory_ = Trajectory(std::move(poses));
  for (OdometryAndEstimate& pair : history_) pair.estimate = T_before_new * pair.estimate;
  last_pose_ = T_before_new * *last_pose_;
  if (previous_pose_) previous_pose_ = T_before_new * *previous_pose_;
  last_moved_pose_ = T_before_new * last_moved_pose_;
  last_update_pose_ = T_before_new * last_update_pose_;
  last_covariance_ = rotate_covariance(last_covariance_, T_before_new.theta());
  ++gap_stats_.relocalized;
  relocalization_.reset();
}

void HectorSlam::abandon_relocalization() {
  earlier_maps_.push_back(relocalization_->before.level(0).to_occupancy_map());
  ++gap_stats_.abandoned;
  relocalization_.reset();
}

OccupancyMap HectorSlam::occupancy_map() const {
  OccupancyMap map;
  for (const OccupancyMap& earlier : earlier_maps_) map = overlay(map, earlier);
  if (relocalization_) map = overlay(map, relocalization_->before.level(0).to_occupancy_map());
  return overlay(map, map_.level(0).to_occupancy_map());
}

}  // namespace slam2d
