// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/rbpf/rbpf_slam.hpp"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <thread>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/scan_preprocessing.hpp"
#include "slam2d/core/thread_sanitizer.hpp"
#include "slam2d/core/resampling.hpp"
#include "slam2d/optim/robust_kernel.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/free_space_check.hpp"

namespace slam2d {

struct RbpfWorkers {
  explicit RbpfWorkers(int count) : threads(count), arena(count) {}
  int threads;
  tbb::task_arena arena;  // max concurrency = the resolved thread count
};

namespace {

MapPyramidConfig map_config(const RbpfConfig& config) {
  MapPyramidConfig map = config.map;
  map.grid.max_range = config.max_range;
  return map;
}

// The per-scan matching of the scan-matched odometry: the proposal's, with its own prior weight
// and rotation multi-start.
RbpfProposalConfig scan_odometry_matching(const RbpfConfig& config) {
  RbpfProposalConfig matching = config.proposal;
  matching.motion_prior_weight = config.scan_odometry_prior_weight;
  if (config.scan_odometry_prior_from_motion_noise) {  // the exact product under Hector's kernel
    matching.motion_prior_weight = 1.0;
    matching.motion_prior_kernel = kOdometryPriorKernel;
  }
  matching.matcher.rotation_search_range = config.scan_odometry_rotation_search;
  matching.matcher.rotation_search_step = config.scan_odometry_rotation_step;
  matching.matcher.rotation_search_margin = config.scan_odometry_rotation_margin;
  return matching;
}

// Independent streams: one per (update, particle), one per update for the resampler (particle = N).
Rng stream(std::uint64_t seed, std::size_t update, std::size_t particle) {
  return Rng(mix_seed(mix_seed(seed) ^ mix_seed((static_cast<std::uint64_t>(update) << 20) ^ particle)));
}

}  // namespace

void validate(const RbpfConfig& config) {
  check_fields(config, "RbpfConfig");
  check(config.max_range > config.min_range, "RbpfConfig: max_range must be > min_range");
  validate(scan_odometry_matching(config).matcher);  // the rotation search's number of starts
  validate(config.proposal);
  validate(config.motion);
  validate(config.scan_odometry_noise);
  validate(config.relocalization);
}

RbpfPathNode::~RbpfPathNode() {
  // Unlink the chain while this node holds its parent's last reference, so that destroying a path
  // of a million nodes does not recurse a million deep.
  std::shared_ptr<RbpfPathNode> next = std::move(parent);
  while (next && next.use_count() == 1) next = std::move(next->parent);
}

RbpfSlam::RbpfSlam(const RbpfConfig& config)
    : config_(config),
      odometry_guard_(config.odometry_guard),
      scan_odometry_noise_(config.scan_odometry_noise),
      scan_odometry_calibration_(config.scan_odometry_calibration),
      gaps_(config.relocalization.gap) {
  validate(config_);
  const int threads = std::min(config_.threads == 0 ? tbb::info::default_concurrency() : config_.threads,
                               config_.particles);
  if (threads > 1) workers_ = std::make_shared<RbpfWorkers>(threads);
  particles_.reserve(static_cast<std::size_t>(config_.particles));
  const MapPyramid empty_map(map_config(config_));
  for (int i = 0; i < config_.particles; ++i) {
    RbpfParticle particle{.T_map_robot = SE2(), .map = empty_map, .path = nullptr};
    particles_.push_back(std::move(particle));
  }
  stats_.neff_min = config_.particles;
  last_neff_ = config_.particles;
}

bool RbpfSlam::needs_update(const SE2& T_odom_robot, double stamp) const {
  if (update_odometry_.empty()) return true;
  const SE2 u = update_odometry_.back().between(T_odom_robot);
  return u.translation().norm() > config_.update_distance || std::abs(normalize_angle(u.theta())) > config_.update_angle ||
         (config_.update_interval > 0.0 && stamp - last_update_stamp_ > config_.update_interval);
}

void RbpfSlam::initialise(const LaserScan& scan, const SE2& T_odom_robot) {
  // Every particle starts at the first odometry pose with the first scan in its map.
  MapPyramid map(map_config(config_));
  map.integrate_scan(scan, T_odom_robot);
  auto node = std::make_shared<RbpfPathNode>(T_odom_robot, 0, nullptr);
  for (RbpfParticle& particle : particles_) {
    particle.T_map_robot = T_odom_robot;
    particle.map = map;  // shares every tile
    particle.path = node;
  }
}

bool RbpfSlam::update_particle(std::size_t i, const LaserScan& scan, const std::vector<Eigen::Vector2d>& points,
                               const SE2& u) {
  RbpfParticle& particle = particles_[i];
  Rng rng = stream(config_.seed, stats_.updates, i);
  SE2 predicted = particle.T_map_robot * u;
  const Eigen::Vector3d sigmas = particle_motion_sigmas(u);
  if (config_.start_noise > 0.0 && stats_.updates > 1) {
    // GMapping's drawFromMotion before the scan matching: each particle starts its match from its
    // own draw of the motion model, so the particles explore different poses and one of them can
    // land in the basin of an old part of the map when a large loop closes.
    const double k = config_.start_noise;
    const Eigen::Vector3d n(rng.gaussian(), rng.gaussian(), rng.gaussian());
    Eigen::Vector3d start(k * sigmas.x() * n.x(), k * sigmas.y() * n.y(), k * sigmas.z() * n.z());
    // Not along a translation the scan leaves open: no match brings a particle back there.
    if (const auto open = scan_open_translation(points, config_.proposal.matcher)) {
      start = without_translation_along(start, *open);
    }
    predicted = predicted * SE2(start.x(), start.y(), start.z());
  }
  const ProposalResult proposal = improved_proposal(particle.map, points, predicted, sigmas, config_.proposal);
  double log_factor = 0.0;
  particle.T_map_robot = sample_pose(proposal, particle.map, points, predicted, sigmas, config_.proposal, rng, log_factor);
  particle.log_weight += log_factor;  // Eq. (19): w_t = w_{t-1} eta
  particle.accumulated_log_weight += log_factor;
  particle.map.integrate_scan(scan, particle.T_map_robot);
  // The previous node may be shared with other particles (resampling copies paths); moving it into
  // the new node changes no reference count and frees nothing, so this is safe in parallel too.
  particle.path = std::make_shared<RbpfPathNode>(proposal_mean(proposal, predicted), stats_.updates, std::move(particle.path));
  return proposal.matched;
}

void RbpfSlam::update_particles(const LaserScan& scan, const std::vector<Eigen::Vector2d>& points, const SE2& u) {
  // Why the parallel loop gives the serial result bit for bit:
  //  - Particle i reads and writes only particles_[i] and draws only from its own generator
  //    stream(seed, update, i), so its computation is the same whatever runs beside it.
  //  - Its map shares tiles with other particles' maps (copied at resampling); TiledGrid makes
  //    concurrent reads and copy-on-write of shared tiles safe and schedule-independent in value
  //    (see TiledGrid::mutable_tile). Its path's previous node may be shared: see update_particle.
  //  - Nothing is accumulated across particles inside the loop: the fallback flags are counted,
  //    and the weights normalised (resample_if_needed), serially in particle order afterwards.
  //  - Nothing is freed in the loop (maps and paths are dropped at resampling, serially).
  const std::size_t n = particles_.size();
  std::vector<unsigned char> matched(n, 0);
  if (!workers_) {
    for (std::size_t i = 0; i < n; ++i) matched[i] = update_particle(i, scan, points, u) ? 1 : 0;
  } else if (kThreadSanitizer) {
    // Debian's libtbb is not built with ThreadSanitizer, which then cannot see TBB's hand-offs
    // and reports every one as a race (the filter's own constructor against the workers' reads).
    // So that TSan checks the particles' code itself, its builds run them on std::threads, whose
    // start and join it sees; every other build uses TBB.
    std::vector<std::thread> threads;
    const auto count = static_cast<std::size_t>(workers_->threads);
    for (std::size_t t = 0; t < count; ++t) {
      threads.emplace_back([&, t] {
        for (std::size_t i = t; i < n; i += count) matched[i] = update_particle(i, scan, points, u) ? 1 : 0;
      });
    }
    for (std::thread& thread : threads) thread.join();
  } else {
    workers_->arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) matched[i] = update_particle(i, scan, points, u) ? 1 : 0;
      });
    });
  }
  for (const unsigned char m : matched) stats_.fallbacks += m ? 0 : 1;
}

bool RbpfSlam::resample_if_needed() {
  std::vector<double> log_weights;
  log_weights.reserve(particles_.size());
  for (const RbpfParticle& particle : particles_) log_weights.push_back(particle.log_weight);
  const std::vector<double> weights = normalized_weights(log_weights);
  last_neff_ = effective_sample_size(weights);  // Eq. (20)
  stats_.neff_min = std::min(stats_.neff_min, last_neff_);
  if (last_neff_ >= config_.resample_threshold * static_cast<double>(particles_.size())) {
    // Keep the weights bounded: shift so that the largest log weight is 0.
    const double max_log = *std::max_element(log_weights.begin(), log_weights.end());
    for (RbpfParticle& particle : particles_) particle.log_weight -= max_log;
    return false;
  }
  Rng rng = stream(config_.seed, stats_.updates, particles_.size());
  const std::vector<std::size_t> drawn = low_variance_resample(weights, rng);
  std::vector<RbpfParticle> next;
  next.reserve(particles_.size());
  for (const std::size_t index : drawn) {
    next.push_back(particles_[index]);  // copies the tile tables, shares the tiles and the path
    next.back().log_weight = 0.0;
  }
  particles_ = std::move(next);
  ++stats_.resamplings;
  return true;
}

// The scan's pose in the odometry frame the filter runs on: the last one moved by the wheel
// odometry's increment when the guard trusts it; a catch-up from the one at the scan where the
// wheel odometry last moved (the catch-up carries the motion since then); else not moved. Then matched
// against the best particle's map (without the motion prior when the increment was not trusted).
// At a catch-up the previous scan's pose competes as a second start and wins with a fit a fifth
// better (kCompetingStartAdvantage, as in Hector): a catch-up over a stall in which the robot
// reversed may carry the reversing wrong (FR079 with a 1.2 s stall every 60 s from +100 s: 0.33 m
// over three seeds, 0.037 m with the second start). So it does at an increment over a pause
// (OdometryCheck::confirm: Intel with its odometry 0.3 s ahead, 1.49 -> 0.020 m).
SE2 RbpfSlam::corrected_odometry(const LaserScan& scan, const OdometryCheck& odometry) {
  SE2 delta;
  if (odometry.trusted()) delta = odometry.increment;
  if (odometry.fault == OdometryFault::kCatchUp) delta = last_corrected_odometry_.between(last_moved_corrected_ * odometry.increment);
  SE2 corrected = last_corrected_odometry_ * delta;
  if (config_.scan_matched_odometry) {
    // The previous scan's pose in the best particle's map, the prediction, the match; after a gap,
    // while the filter waits, in the new map (the same frame: the filter does not move meanwhile).
    const RbpfParticle& particle = best();
    const MapPyramid& map = relocalization_ ? relocalization_->map : particle.map;
    const SE2 previous = particle.T_map_robot * update_odometry_.back().between(last_corrected_odometry_);
    const SE2 predicting = calibrating() && odometry.trusted() ? scan_odometry_calibration_.corrected(delta) : delta;
    const SE2 predicted = previous * predicting;
    const std::vector<Eigen::Vector2d> points = usable_end_points(scan, config_.min_range, config_.max_range);
    RbpfProposalConfig matching = scan_odometry_matching(config_);
    if (!odometry.trusted()) matching.motion_prior_weight = 0.0;
    ProposalResult match;  // none in a new map still empty
    if (!relocalization_ || !relocalization_->map_empty) {
      match = improved_proposal(map, points, predicted, scan_odometry_sigmas(predicting), matching, /*fit=*/false);
    }
    OdometryCheck checked = odometry;  // refuted below when the previous pose wins against a confirmation
    std::optional<SE2> matched = match.matched ? std::optional(match.x_star) : std::nullopt;
    if ((odometry.fault == OdometryFault::kCatchUp || odometry.confirm) && (!relocalization_ || !relocalization_->map_empty)) {
      const ProposalResult second = improved_proposal(map, points, previous, motion_sigmas(SE2(), config_.motion),
                                                      matching, /*fit=*/false);
      const SE2 alternative = second.matched ? second.x_star : previous;
      const double sigma = config_.proposal.likelihood_sigma;
      const double cost = -log_observation_likelihood(map.level(0), points, matched.value_or(predicted), sigma);
      const double alternative_cost = -log_observation_likelihood(map.level(0), points, alternative, sigma);
      if (alternative_cost < kCompetingStartAdvantage * cost) {
        matched = alternative;
        checked.refuted = odometry.confirm;
        if (checked.refuted) odometry_guard_.count_refutation(checked);
      }
    }
    learn_odometry_noise(checked, predicting, previous, match);
    if (matched) corrected = last_corrected_odometry_ * previous.between(*matched);
    learn_odometry_calibration(checked, delta, match, corrected);
    progress_.add(delta, checked.trusted() && !checked.refuted);
    if (!relocalization_ && !update_odometry_.empty() && odometry_refutes_matches(corrected)) {
      corrected = update_odometry_.back() * progress_.odometry();  // the odometry carries the stretch
      ++stats_.stuck_matches;
    }
  }
  last_corrected_odometry_ = corrected;
  if (odometry.moved) last_moved_corrected_ = corrected;
  return corrected;
}

// Whether the odometry since the last update refutes the scan-matched motion to `corrected`
// (core/match_progress.hpp), by the motion model's sigma: matched against a map the filter updates
// only when the matched motion reaches update_distance, a match held back would hold the filter
// (the hospital world's corridor: the robot stood still in the map for 55 s while it drove 22 m;
// 16.0 -> 0.91 m ATE).
bool RbpfSlam::odometry_refutes_matches(const SE2& corrected) const {
  const double sigma = motion_sigmas(progress_.odometry(), config_.motion).x();
  return progress_.refutes(update_odometry_.back().between(corrected), config_.update_distance, sigma);
}

// The motion prior's sigmas for the per-scan matching of the increment `delta`: the motion model's,
// or the learnt odometry noise model's (config.scan_odometry_prior_from_motion_noise).
Eigen::Vector3d RbpfSlam::scan_odometry_sigmas(const SE2& delta) const {
  if (!config_.scan_odometry_prior_from_motion_noise) return motion_sigmas(delta, config_.motion);
  return scan_odometry_noise_.covariance(delta).diagonal().cwiseSqrt();
}

// The motion model's sigmas of the update's increment `u` (x along the travel, y sideways, theta):
// motion's, with the one along the travel from the learnt odometry noise model where it is learnt
// (config.motion_along_from_learnt_noise) and below motion's, not under motion's floor.
Eigen::Vector3d RbpfSlam::particle_motion_sigmas(const SE2& u) const {
  Eigen::Vector3d sigmas = update_sigmas(u, config_.motion);
  if (config_.motion_along_from_learnt_noise && config_.scan_matched_odometry && config_.scan_odometry_prior_from_motion_noise) {
    sigmas.x() = std::clamp(scan_odometry_sigmas(u).x(), config_.motion.min_sigma_translation, sigmas.x());
  }
  return sigmas;
}

// The odometry's noise learnt from a trusted increment and the matched motion since the previous
// scan, whose uncertainty is the two matches' (as Hector's tracker learns it; an unknown one
// teaches nothing).
void RbpfSlam::learn_odometry_noise(const OdometryCheck& odometry, const SE2& delta, const SE2& previous,
                                    const ProposalResult& match) {
  if (!config_.scan_odometry_prior_from_motion_noise) return;
  if (odometry.trusted() && match.matched) {
    scan_odometry_noise_.observe(delta, previous.between(match.x_star),
                                 rotate_covariance(last_match_covariance_ + match.match_covariance, -previous.theta()));
  }
  last_match_covariance_ = match.matched ? match.match_covariance : unknown_covariance();
}

// The odometry's systematic error learnt over stretches of the scan-matched odometry (whose
// motion between two matched scans is the measurement: CalibrationStretches).
void RbpfSlam::learn_odometry_calibration(const OdometryCheck& odometry, const SE2& delta, const ProposalResult& match,
                                          const SE2& corrected) {
  if (!calibrating()) return;
  calibration_stretches_.add(odometry.trusted() && match.matched, delta, scan_odometry_noise_.covariance(delta), corrected,
                             match.match_covariance, scan_odometry_calibration_);
}

RbpfStep RbpfSlam::add_scan(const LaserScan& scan, const SE2& wheel_odometry) {
  const OdometryCheck odometry = odometry_guard_.check(scan.stamp, wheel_odometry);
  const double gap = config_.relocalization.enabled ? gaps_.gap_before(scan.stamp) : 0.0;
  if (gap > 0.0) begin_relocalization(gap);
  if (scans_.empty() && !relocalization_) last_corrected_odometry_ = last_moved_corrected_ = wheel_odometry;
  const SE2 T_odom_robot = scans_.empty() && !relocalization_ ? wheel_odometry : corrected_odometry(scan, odometry);
  const RbpfStep step = relocalization_ ? map_after_gap(scan, T_odom_robot) : filter(scan, T_odom_robot);
  if (!relocalization_) add_to_history(history_, {scan.stamp, wheel_odometry, step.T_map_robot});
  return step;
}

RbpfStep RbpfSlam::filter(const LaserScan& scan, const SE2& T_odom_robot) {
  RbpfStep step;
  if (scans_.empty()) {
    initialise(scan, T_odom_robot);
    update_odometry_.push_back(T_odom_robot);
    last_update_stamp_ = scan.stamp;
    stats_.updates = 1;
    step.updated = true;
  } else if (needs_update(T_odom_robot, scan.stamp)) {
    const SE2 u = update_odometry_.back().between(T_odom_robot);
    const std::vector<Eigen::Vector2d> points = usable_end_points(scan, config_.min_range, config_.max_range);
    update_particles(scan, points, u);
    update_odometry_.push_back(T_odom_robot);
    progress_.restart();
    last_update_stamp_ = scan.stamp;
    step.resampled = resample_if_needed();
    ++stats_.updates;
    step.updated = true;
  }
  scans_.push_back({scan.stamp, T_odom_robot, stats_.updates - 1});
  ++stats_.scans;
  const RbpfParticle& best_particle = best();
  step.T_map_robot = best_particle.path->T_map_robot * update_odometry_.back().between(T_odom_robot);
  step.neff = last_neff_;
  return step;
}

// A gap in the scans ended (the scan being added is the first after it): unless the odometry's
// drift over the gap, measured before it, is within the per-scan matching's reach, the filter
// waits, and the best particle's map is searched for the scans after the gap (SearchBeforeGap). A
// gap while an earlier one is still searched for gives that search up.
void RbpfSlam::begin_relocalization(double gap) {
  ++gap_stats_.gaps;
  if (relocalization_) end_relocalization(std::nullopt);
  if (scans_.empty()) return;
  const GapRelocalizationConfig& c = config_.relocalization;
  const Drift drift = odometry_drift_over(history_, gap);
  if (within_tracker_reach(c.gap, c.sigmas * drift.translation, c.sigmas * drift.rotation)) {
    ++gap_stats_.tracked;
    return;
  }
  history_.clear();
  const RbpfParticle& particle = best();
  relocalization_.emplace(Relocalization{.search = SearchBeforeGap(c, particle.map.level(0), drift),
                                         .T_map_odom = particle.T_map_robot * update_odometry_.back().inverse(),
                                         .map = MapPyramid(map_config(config_))});
}

// A scan after the gap, while the filter waits: into the new map (as an update would, after
// update_distance or update_angle), kept, and searched for in the best particle's map.
RbpfStep RbpfSlam::map_after_gap(const LaserScan& scan, const SE2& T_odom_robot) {
  Relocalization& r = *relocalization_;
  const SE2 pose = r.T_map_odom * T_odom_robot;  // in the new map
  const SE2 moved = r.last_mapped.between(pose);
  if (r.map_empty || moved.translation().norm() > config_.update_distance ||
      std::abs(normalize_angle(moved.theta())) > config_.update_angle) {
    r.map.integrate_scan(scan, pose);
    r.map_empty = false;
    r.last_mapped = pose;
  }
  r.scans.emplace_back(scan, T_odom_robot);
  if (r.scans.size() >= static_cast<std::size_t>(config_.relocalization.max_mapped_scans)) {
    return end_relocalization(std::nullopt);
  }
  const int attempts = r.search.attempts();
  const SearchBeforeGap::Verdict verdict =
      r.search.add(usable_end_points(scan, config_.min_range, config_.max_range), pose, [&] { return wall_points(r.map.level(0)); });
  gap_stats_.attempts += static_cast<std::size_t>(r.search.attempts() - attempts);
  if (verdict.T_before_new || verdict.give_up) return end_relocalization(verdict.T_before_new);
  RbpfStep step;
  step.T_map_robot = pose;
  step.neff = last_neff_;
  return step;
}

// The search ends: found (T_before_new, the new map's pose in the best particle's map), the scans
// since the gap go to the filter moved with it, and each particle matches them in its own map;
// given up, they go to it from the odometry's prediction, into empty maps (the best particle's
// map set aside for the written one).
RbpfStep RbpfSlam::end_relocalization(const std::optional<SE2>& T_before_new) {
  Relocalization r = std::move(*relocalization_);
  relocalization_.reset();
  // T_before_new in the filter's odometry frame.
  const SE2 moved = T_before_new ? r.T_map_odom.inverse() * *T_before_new * r.T_map_odom : SE2();
  if (T_before_new) {
    ++gap_stats_.relocalized;
  } else {
    ++gap_stats_.abandoned;
    earlier_maps_.push_back(best().map.level(0).to_occupancy_map());
    const MapPyramid empty(map_config(config_));
    for (RbpfParticle& particle : particles_) particle.map = empty;
  }
  RbpfStep step;
  for (const auto& [scan, T_odom_robot] : r.scans) step = filter(scan, moved * T_odom_robot);
  last_corrected_odometry_ = moved * last_corrected_odometry_;
  last_moved_corrected_ = moved * last_moved_corrected_;
  return step;
}

OccupancyMap RbpfSlam::occupancy_map() const {
  OccupancyMap map;
  for (const OccupancyMap& earlier : earlier_maps_) map = overlay(map, earlier);
  map = overlay(map, best().map.level(0).to_occupancy_map());
  if (relocalization_) map = overlay(map, relocalization_->map.level(0).to_occupancy_map());
  return map;
}

std::size_t RbpfSlam::best_index() const {
  std::size_t best = 0;
  for (std::size_t i = 1; i < particles_.size(); ++i) {
    if (particles_[i].accumulated_log_weight > particles_[best].accumulated_log_weight) best = i;
  }
  return best;
}

Trajectory RbpfSlam::trajectory() const {
  Trajectory trajectory;
  std::vector<SE2> update_pose(update_odometry_.size());
  for (const RbpfPathNode* node = best().path.get(); node != nullptr; node = node->parent.get()) {
    update_pose[node->update] = node->T_map_robot;
  }
  trajectory.reserve(scans_.size());
  for (const ScanRecord& record : scans_) {
    const std::size_t k = record.update;
    const SE2 since_update = update_odometry_[k].between(record.T_odom_robot);
    const SE2 pose = k + 1 < update_pose.size()
                         ? pose_between_anchors(update_pose[k], update_pose[k + 1],
                                                update_odometry_[k].between(update_odometry_[k + 1]), since_update)
                         : update_pose[k] * since_update;
    trajectory.push_back(record.stamp, pose);
  }
  if (relocalization_) {  // the scans since a gap, while the filter waits: in the new map
    for (const auto& [scan, T_odom_robot] : relocalization_->scans) {
      trajectory.push_back(scan.stamp, relocalization_->T_map_odom * T_odom_robot);
    }
  }
  return trajectory;
}

}  // namespace slam2d
