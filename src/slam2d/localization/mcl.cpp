// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/mcl.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/resampling.hpp"

namespace slam2d {

void validate(const MclConfig& config) {
  check_fields(config, "MclConfig");
  validate(config.beam);  // the weights' sum
  check(config.max_particles >= config.min_particles, "MclConfig: max_particles must be >= min_particles");
  check(config.alpha_slow < config.alpha_fast, "MclConfig: alpha_slow must be < alpha_fast");
}

namespace {

// Low-variance resampling (Table 4.4, core/resampling.hpp): `count` poses drawn from `poses` by
// their weights into `out`.
void draw_low_variance(const std::vector<SE2>& poses, const std::vector<double>& weights, std::size_t count, Rng& rng,
                       std::vector<SE2>& out) {
  out.clear();
  for (const std::size_t i : low_variance_resample(weights, rng, count)) out.push_back(poses[i]);
}

}  // namespace

std::size_t kld_particle_count(std::size_t k, double epsilon, double z) {
  if (k <= 1) return 1;
  // Fox 2003, Eq. (10): chi-square's 1 - delta quantile with k - 1 degrees of freedom over 2 epsilon.
  return static_cast<std::size_t>(std::ceil(chi_square_quantile(static_cast<double>(k - 1), z) / (2.0 * epsilon)));
}

void weighted_pose_statistics(const std::vector<SE2>& poses, const std::vector<double>& weights, SE2* mean,
                              Covariance3* covariance) {
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  double c = 0.0;
  double s = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    t += weights[i] * poses[i].translation();
    const Eigen::Matrix2d R = poses[i].rotation();  // cached cos, sin
    c += weights[i] * R(0, 0);
    s += weights[i] * R(1, 0);
  }
  const double theta = std::atan2(s, c);
  Covariance3 cov = Covariance3::Zero();
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Vector3d d(poses[i].x() - t.x(), poses[i].y() - t.y(), angle_difference(poses[i].theta(), theta));
    cov += weights[i] * d * d.transpose();
  }
  *mean = SE2(t, theta);
  *covariance = cov;
}

MonteCarloLocalization::MonteCarloLocalization(const LocalizationMap& map, const MclConfig& config)
    : map_(map), config_(config), motion_noise_(config.motion, config.motion_noise), rng_(config.seed), status_(config.status) {
  validate(config_);
}

void MonteCarloLocalization::initialize(const SE2& T_map_robot, const Covariance3& covariance) {
  const Eigen::LLT<Eigen::Matrix3d> llt(make_positive_definite(covariance, 1e-12));
  const Eigen::Matrix3d L = llt.matrixL();
  const std::size_t n = std::min(config_.max_particles, std::max<std::size_t>(config_.min_particles, 1000));
  particles_.resize(n);
  for (SE2& p : particles_) {
    const Eigen::Vector3d e = L * Eigen::Vector3d(rng_.gaussian(), rng_.gaussian(), rng_.gaussian());
    p = SE2(T_map_robot.x() + e.x(), T_map_robot.y() + e.y(), T_map_robot.theta() + e.z());
  }
  weights_.assign(n, 1.0 / static_cast<double>(n));
  initialized_ = true;
  started_ = false;
  searching_ = false;
  place_of_.clear();
  place_log_likelihood_.clear();
  averages_started_ = false;
  status_.reset();
  drop_recovery();
  motion_noise_.restart();
}

void MonteCarloLocalization::initialize_global() {
  if (!search_) search_ = std::make_unique<GlobalPoseSearch>(map_, config_.global);
  search_->restart();
  particles_.clear();
  weights_.clear();
  initialized_ = true;
  started_ = false;
  searching_ = true;
  place_of_.clear();
  place_log_likelihood_.clear();
  averages_started_ = false;
  status_.reset();
  drop_recovery();
  motion_noise_.restart();
}

void MonteCarloLocalization::predict(const SE2& increment) {
  const OdometryControl u = motion_noise_.move(increment);
  const Eigen::Vector3d sigmas = control_covariance(u, motion_noise_.model()).diagonal().cwiseSqrt();
  for (SE2& p : particles_) p = sample_odometry_motion(p, u, sigmas, rng_);
  for (SE2& p : recovery_) p = sample_odometry_motion(p, u, sigmas, rng_);
  place_travel_ += std::abs(u.trans);
}

MonteCarloLocalization::SetLikelihood MonteCarloLocalization::weigh_poses(const ScanBeams& beams,
                                                                          const std::vector<SE2>& poses,
                                                                          std::vector<double>& weights) {
  const std::size_t n = poses.size();
  const bool field = config_.sensor == SensorModelKind::kLikelihoodField;
  const double count = static_cast<double>(std::max<std::size_t>(field ? beams.points_robot.size() : beams.ranges.size(), 1));
  if (field) {
    map_.scan_log_likelihoods(beams.points_robot, poses, log_likelihoods_);
  } else {
    log_likelihoods_.resize(n);
    for (std::size_t i = 0; i < n; ++i) log_likelihoods_[i] = beam_model_log_likelihood(map_.map(), beams, poses[i], config_.beam);
  }
  SetLikelihood result;
  for (std::size_t i = 0; i < n; ++i) {
    if (log_likelihoods_[i] > log_likelihoods_[result.best]) result.best = i;
  }
  const double best = log_likelihoods_[result.best];
  weights.resize(n);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    weights[i] = std::exp(config_.likelihood_exponent * (log_likelihoods_[i] - best));
    sum += weights[i];
  }
  for (std::size_t i = 0; i < n; ++i) {
    weights[i] /= sum;
    const double per_beam = std::exp(log_likelihoods_[i] / count);  // the per-beam geometric mean likelihood
    result.mean += per_beam;
    result.weighted += weights[i] * per_beam;
  }
  result.mean /= static_cast<double>(n);
  return result;
}

double MonteCarloLocalization::weigh(const ScanBeams& beams) {
  const SetLikelihood tracked = weigh_poses(beams, particles_, weights_);
  const double w_avg = tracked.mean;
  if (!averages_started_) {
    w_slow_ = w_avg;
    w_fast_ = w_avg;
    averages_started_ = true;
  } else {
    w_slow_ += config_.alpha_slow * (w_avg - w_slow_);  // Table 8.3, line 10
    w_fast_ += config_.alpha_fast * (w_avg - w_fast_);  // line 11
  }
  ++sensor_updates_;
  if (!place_log_likelihood_.empty()) weigh_places();
  if (!recovery_.empty()) weigh_recovery(beams, tracked);
  return w_avg;
}

void MonteCarloLocalization::weigh_places() {
  // p(z | place) is estimated by the mean of its particles' likelihoods (log-sum-exp), summed over
  // the updates (Milstein et al. 2002). Weights: the place posterior times the weight within.
  const std::size_t places = place_log_likelihood_.size();
  std::vector<double> best(places, -std::numeric_limits<double>::infinity());
  std::vector<double> sum(places, 0.0);
  std::vector<std::size_t> count(places, 0);
  for (std::size_t i = 0; i < particles_.size(); ++i) best[place_of_[i]] = std::max(best[place_of_[i]], config_.likelihood_exponent * log_likelihoods_[i]);
  within_weights_.resize(particles_.size());
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    const std::uint32_t p = place_of_[i];
    within_weights_[i] = std::exp(config_.likelihood_exponent * log_likelihoods_[i] - best[p]);
    sum[p] += within_weights_[i];
    ++count[p];
  }
  // The evidence counts once the places have settled: before, a place's marginal likelihood says
  // more about how well its few particles happened to be drawn than about the place.
  const bool counts = ++place_updates_ > config_.place_settle_updates;
  double leader = -std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < places; ++p) {
    if (count[p] == 0) continue;
    if (counts) place_log_likelihood_[p] += best[p] + std::log(sum[p] / static_cast<double>(count[p]));
    leader = std::max(leader, place_log_likelihood_[p]);
  }
  // A place that fell place_margin behind the leader is dropped (it gets no particles at resampling).
  double total = 0.0;
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    const std::uint32_t p = place_of_[i];
    const double lag = place_log_likelihood_[p] - leader;
    within_weights_[i] /= sum[p];
    weights_[i] = lag < -config_.place_margin && places_decidable() ? 0.0 : within_weights_[i] * std::exp(lag);
    total += weights_[i];
  }
  for (double& w : weights_) w /= total;
}

void MonteCarloLocalization::resample_places() {
  const double leader = *std::max_element(place_log_likelihood_.begin(), place_log_likelihood_.end());
  // The places kept, with their particles (and weights within) gathered.
  std::vector<std::vector<SE2>> members(place_log_likelihood_.size());
  std::vector<std::vector<double>> member_weights(place_log_likelihood_.size());
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    members[place_of_[i]].push_back(particles_[i]);
    member_weights[place_of_[i]].push_back(within_weights_[i]);
  }
  std::vector<std::size_t> kept;  // best first
  for (std::size_t p = 0; p < members.size(); ++p) {
    if (!members[p].empty() && (place_log_likelihood_[p] >= leader - config_.place_margin || !places_decidable())) kept.push_back(p);
  }
  std::stable_sort(kept.begin(), kept.end(), [&](std::size_t a, std::size_t b) { return place_log_likelihood_[a] > place_log_likelihood_[b]; });
  // A place whose mean met a better place's joins it, its weights scaled by the evidence ratio.
  std::vector<std::size_t> merged;
  std::vector<SE2> means;
  for (const std::size_t p : kept) {
    SE2 mean;
    Covariance3 unused;
    weighted_pose_statistics(members[p], member_weights[p], &mean, &unused);
    std::size_t q = 0;
    while (q < merged.size() && ((mean.translation() - means[q].translation()).norm() > config_.place_radius_xy ||
                                 std::abs(angle_difference(mean.theta(), means[q].theta())) > config_.place_radius_theta)) {
      ++q;
    }
    if (q == merged.size()) {
      merged.push_back(p);
      means.push_back(mean);
      continue;
    }
    const std::size_t better = merged[q];
    const double ratio = std::exp(place_log_likelihood_[p] - place_log_likelihood_[better]);
    for (std::size_t k = 0; k < members[p].size(); ++k) {
      members[better].push_back(members[p][k]);
      member_weights[better].push_back(ratio * member_weights[p][k]);
    }
  }
  // Equal shares: no place starves because another explained the last scans a little better.
  const std::size_t share = std::max<std::size_t>(1, config_.max_particles / merged.size());
  particles_.clear();
  place_of_.clear();
  std::vector<double> log_likelihoods;
  for (std::size_t m = 0; m < merged.size(); ++m) {
    const std::size_t p = merged[m];
    double total = 0.0;
    for (const double w : member_weights[p]) total += w;
    for (double& w : member_weights[p]) w /= total;
    draw_low_variance(members[p], member_weights[p], share, rng_, scratch_);
    particles_.insert(particles_.end(), scratch_.begin(), scratch_.end());
    place_of_.insert(place_of_.end(), share, static_cast<std::uint32_t>(m));
    log_likelihoods.push_back(place_log_likelihood_[p]);
  }
  place_log_likelihood_ = log_likelihoods;
  weights_.assign(particles_.size(), 1.0 / static_cast<double>(particles_.size()));
  if (place_log_likelihood_.size() <= 1) {  // one place left: it dominates; plain MCL from here
    place_log_likelihood_.clear();
    place_of_.clear();
  }
}

void MonteCarloLocalization::weigh_recovery(const ScanBeams& beams, const SetLikelihood& tracked) {
  const SetLikelihood recovery = weigh_poses(beams, recovery_, recovery_weights_);
  // The recovery set wins an update when it would itself count as localized (compact and plausible
  // at its mean, the criteria of LocalizationStatus) and explains the scan better.
  SE2 mean;
  Covariance3 covariance;
  weighted_pose_statistics(recovery_, recovery_weights_, &mean, &covariance);
  const double sigma_xy = std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(covariance.topLeftCorner<2, 2>()).eigenvalues().maxCoeff());
  const bool compact = sigma_xy <= config_.status.max_sigma_xy && std::sqrt(covariance(2, 2)) <= config_.status.max_sigma_theta;
  recovery_better_ = recovery.weighted > tracked.weighted;
  const bool wins = recovery_better_ && compact &&
                    map_.plausibility(beams.points_robot, mean, config_.status.plausibility_distance) >= config_.status.min_plausibility;
  recovery_wins_ = wins ? recovery_wins_ + 1 : 0;
  if (recovery_wins_ < config_.takeover_updates) return;
  particles_.swap(recovery_);
  weights_.swap(recovery_weights_);
  // The short-term average restarts at the new set's likelihood, so injection stops at once. The
  // old tracked set becomes the alternative: it wins back if the takeover was wrong.
  w_fast_ = std::max(w_fast_, recovery.weighted);
  ++takeovers_;
  recovery_wins_ = 0;
  recovery_better_ = false;
  updates_since_injection_ = 0;
  displaced_ = true;
}

void MonteCarloLocalization::drop_recovery() {
  recovery_.clear();
  recovery_weights_.clear();
  recovery_wins_ = 0;
  recovery_better_ = false;
  updates_since_injection_ = 0;
  displaced_ = false;
}

void MonteCarloLocalization::update_recovery(double p_inject) {
  injected_last_ = 0;
  if (p_inject <= 0.0) {
    // A kidnap into a look-alike place lowers the likelihood only for a moment: the set searches
    // on for recovery_updates after the last injection, and as long as it explains the scan better.
    // A displaced tracked set stays longer: the map may have explained its place badly for a while.
    if (recovery_.empty()) return;
    const int keep = displaced_ ? config_.displaced_updates : config_.recovery_updates;
    if (++updates_since_injection_ >= keep && !recovery_better_) {
      drop_recovery();
      return;
    }
  } else {
    updates_since_injection_ = 0;
    displaced_ = false;
  }
  if (recovery_.empty()) {
    recovery_.resize(config_.max_particles);
    for (SE2& p : recovery_) p = map_.sample_free_pose(rng_);
    injected_last_ = recovery_.size();
  } else {
    draw_low_variance(recovery_, recovery_weights_, config_.max_particles, rng_, scratch_);
    recovery_.swap(scratch_);
    for (SE2& p : recovery_) {
      if (p_inject > 0.0 && rng_.bernoulli(p_inject)) {
        p = map_.sample_free_pose(rng_);
        ++injected_last_;
      }
    }
  }
  recovery_weights_.assign(recovery_.size(), 1.0 / static_cast<double>(recovery_.size()));
}

LocalizationEstimate MonteCarloLocalization::summarize(const ScanBeams& beams) {
  LocalizationEstimate estimate;
  weighted_pose_statistics(particles_, weights_, &estimate.pose, &estimate.covariance);
  if (!place_log_likelihood_.empty()) {
    // Several places: the pose is the leading place's mean (the mean of all would lie between
    // them); the covariance stays the spread of all of them.
    const auto leader = static_cast<std::uint32_t>(
        std::max_element(place_log_likelihood_.begin(), place_log_likelihood_.end()) - place_log_likelihood_.begin());
    std::vector<SE2> poses;
    std::vector<double> weights;
    for (std::size_t i = 0; i < particles_.size(); ++i) {
      if (place_of_[i] != leader) continue;
      poses.push_back(particles_[i]);
      weights.push_back(within_weights_[i]);
    }
    Covariance3 unused;
    weighted_pose_statistics(poses, weights, &estimate.pose, &unused);
  }
  estimate.plausibility = map_.plausibility(beams.points_robot, estimate.pose, config_.status.plausibility_distance);
  // Not localized either while the recovery set searches, or while the set it displaced explains
  // the scan better: the filter doubts its place.
  const bool doubt = !recovery_.empty() && (!displaced_ || recovery_better_);
  // While several candidate places are tracked, none dominates: not localized.
  const bool likely = !(w_fast_ < config_.min_likelihood_ratio * w_slow_) && !doubt && place_log_likelihood_.empty();
  estimate.localized = status_.update(estimate.covariance, likely ? estimate.plausibility : 0.0);
  return estimate;
}

void MonteCarloLocalization::resample() {
  if (!place_log_likelihood_.empty()) {
    resample_places();
    return;
  }
  std::size_t target = config_.max_particles;
  if (config_.kld_sampling) {
    draw_low_variance(particles_, weights_, std::max(particles_.size(), config_.min_particles), rng_, scratch_);
    std::vector<std::uint64_t> bins;
    bins.reserve(scratch_.size());
    for (const SE2& p : scratch_) {
      const auto bx = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(p.x() / config_.kld_bin_xy)) & 0x1FFFFF);
      const auto by = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(p.y() / config_.kld_bin_xy)) & 0x1FFFFF);
      const auto bt = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(p.theta() / config_.kld_bin_theta)) & 0x3FFFFF);
      bins.push_back(bx << 43 | by << 22 | bt);
    }
    std::sort(bins.begin(), bins.end());
    const std::size_t k = static_cast<std::size_t>(std::unique(bins.begin(), bins.end()) - bins.begin());
    target = std::clamp(kld_particle_count(k, config_.kld_epsilon, config_.kld_z), config_.min_particles,
                        config_.max_particles);
  }
  draw_low_variance(particles_, weights_, target, rng_, scratch_);
  particles_.swap(scratch_);
  weights_.assign(particles_.size(), 1.0 / static_cast<double>(particles_.size()));
  // Augmented MCL (Table 8.3, line 13): random poses with probability max(0, 1 - w_fast / w_slow),
  // here into the recovery set.
  const double p_inject =
      config_.augmented && w_slow_ > 0.0 ? std::min(config_.max_injection, std::max(0.0, 1.0 - w_fast_ / (config_.injection_ratio * w_slow_))) : 0.0;
  update_recovery(p_inject);
}

LocalizationEstimate MonteCarloLocalization::search_update(const SE2& T_odom_robot, const LaserScan& scan) {
  if (!started_) odom_at_start_ = T_odom_robot;
  started_ = true;
  odom_at_update_ = T_odom_robot;
  const ScanBeams coarse = select_beams(scan, config_.global.max_beams, config_.usable_range);
  search_->add_scan(coarse.points_robot, odom_at_start_.between(T_odom_robot));
  if (!search_->done()) {
    ++sensor_updates_;
    // Not localized while the candidates are spread over the map; the best one as the estimate.
    LocalizationEstimate estimate;
    SE2 mean;
    search_->spread(config_.min_particles, &mean, &estimate.covariance);
    estimate.pose = search_->best();
    estimate.plausibility = map_.plausibility(coarse.points_robot, estimate.pose, config_.status.plausibility_distance);
    estimate_ = estimate;
    return estimate_;
  }
  // The fine pass: the particle filter, seeded around the best hypotheses, weighs this scan.
  searching_ = false;
  const std::vector<std::vector<SE2>> places = search_->seed_places(
      config_.max_particles, std::min(config_.max_places, config_.max_particles), config_.max_particles,
      config_.place_radius_xy, config_.place_radius_theta, rng_);
  particles_.clear();
  place_of_.clear();
  for (std::size_t p = 0; p < places.size(); ++p) {
    particles_.insert(particles_.end(), places[p].begin(), places[p].end());
    place_of_.insert(place_of_.end(), places[p].size(), static_cast<std::uint32_t>(p));
  }
  place_log_likelihood_.assign(places.size() > 1 ? places.size() : 0, 0.0);
  place_updates_ = 0;
  place_travel_ = 0.0;
  if (places.size() <= 1) place_of_.clear();
  weights_.assign(particles_.size(), 1.0 / static_cast<double>(particles_.size()));
  const ScanBeams beams = select_beams(scan, config_.max_beams, config_.usable_range);
  weigh(beams);
  estimate_ = summarize(beams);
  resample();
  return estimate_;
}

LocalizationEstimate MonteCarloLocalization::update(const SE2& T_odom_robot, const LaserScan& scan) {
  check(initialized_, "mcl: initialize() or initialize_global() before update()");
  if (searching_ && (!started_ || moved_enough(odom_at_update_, T_odom_robot, config_.update_distance, config_.update_angle))) {
    return search_update(T_odom_robot, scan);
  }
  if (started_) {
    if (!moved_enough(odom_at_update_, T_odom_robot, config_.update_distance, config_.update_angle)) {
      return follow_odometry(estimate_, motion_noise_.corrected(odom_at_update_.between(T_odom_robot)));
    }
    predict(odom_at_update_.between(T_odom_robot));
  }
  started_ = true;
  odom_at_update_ = T_odom_robot;
  const ScanBeams beams = select_beams(scan, config_.max_beams, config_.usable_range);
  weigh(beams);
  estimate_ = summarize(beams);
  // The learner's measurement, made only where a stretch ends and only while localized on one
  // place (a match at the mean of two places, or of a lost set, is no measurement).
  if (motion_noise_.wants_measurement()) {
    const bool one_place = estimate_.localized && !searching_ && place_log_likelihood_.empty();
    motion_noise_.measured(one_place ? map_.match(beams.points_robot, estimate_.pose, config_.motion_noise_matcher) : std::nullopt);
  }
  resample();
  return estimate_;
}

}  // namespace slam2d
