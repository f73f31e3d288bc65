#include "slam2d/localization/mcl.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

void validate(const MclConfig& config) {
  validate(config.motion);
  validate(config.beam);
  check(config.max_beams > 0, "mcl: max_beams must be > 0");
  check(config.likelihood_exponent > 0.0 && config.likelihood_exponent <= 1.0, "mcl: likelihood_exponent must be in (0, 1]");
  check(config.usable_range > 0.0, "mcl: usable_range must be > 0");
  check(config.min_particles >= 1 && config.max_particles >= config.min_particles,
        "mcl: need 1 <= min_particles <= max_particles");
  check(config.kld_epsilon > 0.0 && config.kld_bin_xy > 0.0 && config.kld_bin_theta > 0.0,
        "mcl: kld_epsilon and the bin sizes must be > 0");
  check(config.update_distance >= 0.0 && config.update_angle >= 0.0, "mcl: update thresholds must be >= 0");
  check(config.alpha_slow > 0.0 && config.alpha_slow < config.alpha_fast && config.alpha_fast <= 1.0,
        "mcl: need 0 < alpha_slow < alpha_fast <= 1");
  check(config.max_injection >= 0.0 && config.max_injection <= 1.0, "mcl: max_injection must be in [0, 1]");
  check(config.injection_ratio > 0.0 && config.injection_ratio <= 1.0, "mcl: injection_ratio must be in (0, 1]");
  check(config.takeover_updates >= 1 && config.recovery_updates >= 1 && config.displaced_updates >= 1,
        "mcl: takeover_updates, recovery_updates and displaced_updates must be >= 1");
  check(config.status.lost_after >= 1, "mcl: status.lost_after must be >= 1");
}

namespace {

// Low-variance resampling (Table 4.4): `count` poses drawn from `poses` by their weights into `out`.
void draw_low_variance(const std::vector<SE2>& poses, const std::vector<double>& weights, std::size_t count, Rng& rng,
                       std::vector<SE2>& out) {
  out.clear();
  const double step = 1.0 / static_cast<double>(count);
  double r = rng.uniform(0.0, step);
  double c = weights[0];
  std::size_t i = 0;
  for (std::size_t m = 0; m < count; ++m) {
    const double u = r + static_cast<double>(m) * step;
    while (u > c && i + 1 < poses.size()) c += weights[++i];
    out.push_back(poses[i]);
  }
}

}  // namespace

std::size_t kld_particle_count(std::size_t k, double epsilon, double z) {
  if (k <= 1) return 1;
  const double km1 = static_cast<double>(k - 1);
  const double a = 2.0 / (9.0 * km1);
  const double b = 1.0 - a + std::sqrt(a) * z;
  return static_cast<std::size_t>(std::ceil(km1 / (2.0 * epsilon) * b * b * b));  // Fox 2003, Eq. (10)
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
    : map_(map), config_(config), rng_(config.seed), status_(config.status) {
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
  status_.reset();
  drop_recovery();
}

void MonteCarloLocalization::initialize_global() {
  particles_.resize(config_.max_particles);
  for (SE2& p : particles_) p = map_.sample_free_pose(rng_);
  weights_.assign(particles_.size(), 1.0 / static_cast<double>(particles_.size()));
  initialized_ = true;
  started_ = false;
  status_.reset();
  drop_recovery();
}

void MonteCarloLocalization::predict(const OdometryControl& u) {
  const Eigen::Vector3d sigmas = control_covariance(u, config_.motion).diagonal().cwiseSqrt();
  for (SE2& p : particles_) p = sample_odometry_motion(p, u, sigmas, rng_);
  for (SE2& p : recovery_) p = sample_odometry_motion(p, u, sigmas, rng_);
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
  if (sensor_updates_ == 0) {
    w_slow_ = w_avg;
    w_fast_ = w_avg;
  } else {
    w_slow_ += config_.alpha_slow * (w_avg - w_slow_);  // Table 8.3, line 10
    w_fast_ += config_.alpha_fast * (w_avg - w_fast_);  // line 11
  }
  ++sensor_updates_;
  if (!recovery_.empty()) weigh_recovery(beams, tracked);
  return w_avg;
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
  estimate.plausibility = map_.plausibility(beams.points_robot, estimate.pose, config_.status.plausibility_distance);
  // Not localized either while the recovery set searches, or while the set it displaced explains
  // the scan better: the filter doubts its place.
  const bool doubt = !recovery_.empty() && (!displaced_ || recovery_better_);
  const bool likely = !(w_fast_ < config_.min_likelihood_ratio * w_slow_) && !doubt;
  estimate.localized = status_.update(estimate.covariance, likely ? estimate.plausibility : 0.0);
  return estimate;
}

void MonteCarloLocalization::resample() {
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

LocalizationEstimate MonteCarloLocalization::update(const SE2& T_odom_robot, const LaserScan& scan) {
  check(initialized_, "mcl: initialize() or initialize_global() before update()");
  if (started_) {
    if (!moved_enough(odom_at_update_, T_odom_robot, config_.update_distance, config_.update_angle)) {
      return follow_odometry(estimate_, odom_at_update_, T_odom_robot);
    }
    predict(decompose_odometry(odom_at_update_, T_odom_robot));
  }
  started_ = true;
  odom_at_update_ = T_odom_robot;
  const ScanBeams beams = select_beams(scan, config_.max_beams, config_.usable_range);
  weigh(beams);
  estimate_ = summarize(beams);
  resample();
  return estimate_;
}

}  // namespace slam2d
