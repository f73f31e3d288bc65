// SPDX-License-Identifier: BSD-3-Clause
// GA + ICP hybrid (Martinez et al., J. Field Robotics 2006); see the header for the equations.
#include "slam2d/registration/ga_icp.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/registration/icp.hpp"

namespace slam2d {
namespace {

constexpr std::size_t kMinCloudPoints = 3;
constexpr int kGenes = 3;
constexpr double kMinIncrement = 1e-4;  // rad: a finer inferred beam spacing is taken as this
constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// An angle in [0, 2 pi).
double wrap_positive(double angle) {
  const double wrapped = normalize_angle(angle);
  return wrapped < 0.0 ? wrapped + kTwoPi : wrapped;
}

int total_bits(const GaIcpConfig& config) { return kGenes * config.bits_per_gene; }
std::uint64_t all_bits(const GaIcpConfig& config) { return (std::uint64_t{1} << total_bits(config)) - 1; }

SE2 candidate_pose(const SE2& guess, const Eigen::Vector3d& offset) {
  return SE2(guess.x() + offset.x(), guess.y() + offset.y(), guess.theta() + offset.z());
}

struct Individual {
  std::uint64_t chromosome = 0;
  double error = 0.0;  // m^2, Eq. (2)-(3)
};

bool fitter(const Individual& a, const Individual& b) {
  return a.error < b.error || (a.error == b.error && a.chromosome < b.chromosome);
}

/// Eq. (2)-(3) of a chromosome's pose, memoised (short chromosomes repeat often).
class Fitness {
 public:
  Fitness(const PointCloud2& target, const RangeDifferenceMetric& metric, const SE2& guess, const GaIcpConfig& config)
      : target_(target), metric_(metric), guess_(guess), config_(config) {}

  double operator()(std::uint64_t chromosome) {
    const auto [it, inserted] = cache_.try_emplace(chromosome, 0.0);
    if (inserted) it->second = metric_.score(target_, pose(chromosome)).error;
    return it->second;
  }
  SE2 pose(std::uint64_t chromosome) const {
    return candidate_pose(guess_, decode_chromosome(chromosome, config_));
  }
  std::size_t evaluations() const { return cache_.size(); }

 private:
  const PointCloud2& target_;
  const RangeDifferenceMetric& metric_;
  SE2 guess_;
  const GaIcpConfig& config_;
  std::unordered_map<std::uint64_t, double> cache_;
};

/// Uniformly random chromosomes, sorted fittest first.
std::vector<Individual> initial_population(Rng& rng, const GaIcpConfig& config, Fitness& fitness) {
  std::vector<Individual> population(static_cast<std::size_t>(config.population));
  for (Individual& individual : population) {
    individual.chromosome = rng.next_u64() & all_bits(config);
    individual.error = fitness(individual.chromosome);
  }
  std::sort(population.begin(), population.end(), fitter);
  return population;
}

/// Tournament selection: the fittest of k random draws, i.e. the smallest index of a sorted population.
std::uint64_t select_parent(Rng& rng, const std::vector<Individual>& sorted, const GaIcpConfig& config) {
  std::size_t best = sorted.size();
  for (int draw = 0; draw < config.tournament_size; ++draw) best = std::min(best, rng.uniform_index(sorted.size()));
  return sorted[best].chromosome;
}

/// One-point crossover over the whole chromosome: the low bits of one parent, the high of the other.
void crossover(Rng& rng, std::uint64_t& a, std::uint64_t& b, const GaIcpConfig& config) {
  const auto point = 1 + rng.uniform_index(static_cast<std::size_t>(total_bits(config) - 1));
  const std::uint64_t low = (std::uint64_t{1} << point) - 1;
  const std::uint64_t high = all_bits(config) & ~low;
  const std::uint64_t child_a = (a & low) | (b & high);
  const std::uint64_t child_b = (b & low) | (a & high);
  a = child_a;
  b = child_b;
}

/// Bit-flip mutation, each bit with probability mutation_rate.
void mutate(Rng& rng, std::uint64_t& chromosome, const GaIcpConfig& config) {
  for (int bit = 0; bit < total_bits(config); ++bit) {
    if (rng.bernoulli(config.mutation_rate)) chromosome ^= std::uint64_t{1} << bit;
  }
}

/// Elitism, then couples by tournament, crossed and mutated, until the population is full.
std::vector<Individual> next_generation(Rng& rng, const std::vector<Individual>& sorted, const GaIcpConfig& config,
                                        Fitness& fitness) {
  const auto size = static_cast<std::size_t>(config.population);
  std::vector<Individual> next(sorted.begin(), sorted.begin() + config.elite);
  while (next.size() < size) {
    std::uint64_t a = select_parent(rng, sorted, config);
    std::uint64_t b = select_parent(rng, sorted, config);
    if (rng.bernoulli(config.crossover_rate)) crossover(rng, a, b, config);
    mutate(rng, a, config);
    mutate(rng, b, config);
    next.push_back({a, fitness(a)});
    if (next.size() < size) next.push_back({b, fitness(b)});
  }
  std::sort(next.begin(), next.end(), fitter);
  return next;
}

MatchResult failed_match(const SE2& guess) {
  MatchResult result;
  result.T_target_source = guess;
  result.converged = false;
  result.degenerate = true;
  return result;
}

}  // namespace

void validate(const GaIcpConfig& c) {
  check_fields(c, "GaIcpConfig");
  check(c.elite < c.population, "GaIcpConfig: elite must be < population");
}

Eigen::Vector3d decode_chromosome(std::uint64_t chromosome, const GaIcpConfig& config) {
  const int bits = config.bits_per_gene;
  const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
  const Eigen::Vector3d window(config.window_x, config.window_y, config.window_theta);
  Eigen::Vector3d offset;
  for (int gene = 0; gene < kGenes; ++gene) {
    const auto k = static_cast<double>((chromosome >> (gene * bits)) & mask);
    offset[gene] = -window[gene] + 2.0 * window[gene] * k / static_cast<double>(mask);  // Eq. (1)
  }
  return offset;
}

RangeDifferenceMetric::RangeDifferenceMetric(const PointCloud2& source, const GaIcpConfig& config)
    : max_range_difference_(config.max_range_difference), min_matching_index_(config.min_matching_index) {
  std::vector<double> bearings, ranges;
  for (const Point2& p : source.points) {
    if (p.norm() <= 0.0) continue;
    bearings.push_back(std::atan2(p.y(), p.x()));
    ranges.push_back(p.norm());
  }
  if (bearings.empty()) return;
  first_bearing_ = bearings.front();
  const double direction = bearings.size() > 1 && angle_difference(bearings[1], bearings[0]) < 0.0 ? -1.0 : 1.0;
  std::vector<double> relative(bearings.size());
  double spacing = kTwoPi, span = 0.0;
  for (std::size_t i = 0; i < bearings.size(); ++i) {
    relative[i] = wrap_positive(direction * (bearings[i] - first_bearing_));
    span = std::max(span, relative[i]);
    if (i > 0 && relative[i] - relative[i - 1] > 1e-9) spacing = std::min(spacing, relative[i] - relative[i - 1]);
  }
  if (config.angular_resolution > 0.0) spacing = config.angular_resolution;
  increment_ = direction * std::max(spacing, kMinIncrement);
  ranges_.assign(static_cast<std::size_t>(std::llround(span / std::abs(increment_))) + 1, 0.0);
  for (std::size_t i = 0; i < relative.size(); ++i) {
    double& beam = ranges_[std::min(ranges_.size() - 1, static_cast<std::size_t>(std::llround(relative[i] / std::abs(increment_))))];
    if (beam == 0.0) ++readings_;
    beam = beam == 0.0 ? ranges[i] : std::min(beam, ranges[i]);
  }
}

std::size_t RangeDifferenceMetric::beam_of(double bearing) const {
  const double step = std::abs(increment_);
  const double relative = wrap_positive((increment_ < 0.0 ? -1.0 : 1.0) * (bearing - first_bearing_));
  const auto beam = static_cast<std::size_t>(std::llround(relative / step));
  if (beam < ranges_.size()) return beam;
  return kTwoPi - relative <= 0.5 * step ? 0 : ranges_.size();  // just before the first beam
}

RangeDifferenceScore RangeDifferenceMetric::score(const PointCloud2& target, const SE2& T_target_source) const {
  RangeDifferenceScore score;
  if (readings_ == 0) return score;
  std::vector<double> projected(ranges_.size(), std::numeric_limits<double>::infinity());
  const SE2 T_source_target = T_target_source.inverse();
  for (const Point2& q : target.points) {  // the target as the source's sensor would see it
    const Point2 p = T_source_target * q;
    const std::size_t beam = beam_of(std::atan2(p.y(), p.x()));
    if (beam < projected.size()) projected[beam] = std::min(projected[beam], p.norm());
  }
  double sum = 0.0;  // of the matched readings' squared differences
  for (std::size_t k = 0; k < ranges_.size(); ++k) {
    if (ranges_[k] == 0.0 || !(std::abs(ranges_[k] - projected[k]) <= max_range_difference_)) continue;
    const double difference = ranges_[k] - projected[k];
    sum += difference * difference;
    ++score.matched_readings;
  }
  const auto matched = static_cast<double>(score.matched_readings);
  score.matching_index = matched / static_cast<double>(readings_);
  if (score.matched_readings > 0) score.matched_rms = std::sqrt(sum / matched);
  if (score.matched_readings > 0 && score.matching_index >= min_matching_index_) {  // Eq. (3)
    const double I = score.matching_index;
    score.error = I * (sum / matched) + (1.0 - I) * max_range_difference_ * max_range_difference_;  // Eq. (2)
  }
  return score;
}

GaSearchResult ga_search(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                         const GaIcpConfig& config) {
  validate(config);
  const RangeDifferenceMetric metric(source, config);
  GaSearchResult result{T_target_source_guess, metric.score(target, T_target_source_guess), 0, 1};
  if (target.size() < kMinCloudPoints || source.size() < kMinCloudPoints) return result;
  Rng rng(config.seed);
  Fitness fitness(target, metric, T_target_source_guess, config);
  std::vector<Individual> population = initial_population(rng, config, fitness);
  for (int generation = 0; generation < config.generations; ++generation) {
    population = next_generation(rng, population, config, fitness);
  }
  result.generations = config.generations;
  result.evaluations += fitness.evaluations();
  if (population.front().error < result.score.error) {  // else the guess itself scores best
    result.T_target_source = fitness.pose(population.front().chromosome);
    result.score = metric.score(target, result.T_target_source);
  }
  return result;
}

double icp_gate(const GaSearchResult& search, const GaIcpConfig& config) {
  const double upper = config.icp_max_correspondence_distance;
  if (!std::isfinite(search.score.error) || config.icp_gate_factor == 0.0) return upper;
  return std::clamp(config.icp_gate_factor * search.score.matched_rms, std::min(config.icp_min_correspondence_distance, upper),
                    upper);  // Eq. (4)
}

MatchResult match_ga_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                         const GaIcpConfig& config) {
  validate(config);
  if (target.size() < kMinCloudPoints || source.size() < kMinCloudPoints) return failed_match(T_target_source_guess);
  const GaSearchResult search = ga_search(target, source, T_target_source_guess, config);  // the GA stage
  const IcpConfig icp{.max_iterations = config.icp_max_iterations,
                      .max_correspondence_distance = icp_gate(search, config),
                      .min_correspondences = config.icp_min_correspondences};
  MatchResult result = match_icp(target, source, search.T_target_source, icp);  // the ICP stage
  result.iterations += search.generations;
  return result;
}

}  // namespace slam2d
