// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/odometry_time_offset.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <utility>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/jackknife.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/number_text.hpp"
#include "slam2d/core/odometry_chain.hpp"
#include "slam2d/registration/pl_icp.hpp"

namespace slam2d {

void validate(const OdometryTimeOffsetConfig& config) { check_fields(config, "OdometryTimeOffsetConfig"); }

namespace {

// One scan pair: its heading change as the scans see it, and where its scans sit in the chain.
struct HeadingPair {
  std::size_t first = 0;   // chain entries of the two scans
  std::size_t second = 0;
  double turn = 0.0;       // rad, dtheta_j: the heading change the scans show
  std::size_t group = 0;   // jackknife group (of its window)
};

// Step 1: the scan stride s giving pairs about pair_span apart (by the median scan period).
std::size_t pair_stride(const OdometryChain& chain, const std::vector<std::size_t>& scans, double pair_span) {
  std::vector<double> periods;
  for (std::size_t i = 1; i < scans.size(); ++i) {
    const double dt = chain[scans[i]].stamp - chain[scans[i - 1]].stamp;
    if (dt > 0.0) periods.push_back(dt);
  }
  if (periods.empty()) return 1;
  std::nth_element(periods.begin(), periods.begin() + static_cast<long>(periods.size() / 2), periods.end());
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(pair_span / periods[periods.size() / 2])));
}

// Step 1: the first scan index (into `scans`) of each window; pairs (j, j + s) chain along it.
// Every window when they hold at most max_pairs pairs, else that many windows spread evenly.
std::vector<std::size_t> window_starts(std::size_t scan_count, std::size_t stride, const OdometryTimeOffsetConfig& config) {
  if (scan_count <= stride) return {};
  const std::size_t window_scans = config.window_pairs * stride;  // the scans a window spans
  const std::size_t all_windows = (scan_count - 1 + window_scans - 1) / window_scans;
  const std::size_t wanted = std::max<std::size_t>(2, config.max_pairs / config.window_pairs);
  std::vector<std::size_t> starts;
  if (all_windows <= wanted) {
    for (std::size_t w = 0; w < all_windows; ++w) starts.push_back(w * window_scans);
    return starts;
  }
  const std::size_t last_start = scan_count - 1 - window_scans;  // all_windows > 2: no underflow
  for (std::size_t w = 0; w < wanted; ++w) starts.push_back(w * last_start / (wanted - 1));
  return starts;
}

// The scan's points in its sensor frame, readings beyond max_range dropped, every k-th beam kept
// so that at most max_points remain (beam order kept, for PL-ICP's projective search).
PointCloud2 usable_cloud(const LaserScan& scan, const OdometryTimeOffsetConfig& config) {
  PointCloud2 cloud = to_point_cloud(scan, ScanFrame::kSensor).cloud;
  std::erase_if(cloud.points, [&](const Point2& p) { return !(p.norm() < config.max_range); });
  const std::size_t k = (cloud.size() + config.max_points - 1) / config.max_points;
  if (k > 1) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < cloud.size(); i += k) cloud.points[kept++] = cloud.points[i];
    cloud.points.resize(kept);
  }
  return cloud;
}

// Step 2: one PL-ICP match between two scans (target, source) from `guess`, if it passes the gate.
std::optional<SE2> gated_match(const PointCloud2& target, const PointCloud2& source, const SE2& guess,
                               const OdometryTimeOffsetConfig& config) {
  if (target.size() < 10 || source.size() < 10) return std::nullopt;
  const MatchResult match = match_pl_icp(target, source, guess);
  const bool passes = match.converged && match.residual <= config.max_residual &&
                      static_cast<double>(match.inliers) >= config.min_inlier_fraction * static_cast<double>(source.size());
  return passes ? std::optional<SE2>(match.T_target_source) : std::nullopt;
}

// Step 1: the pairs (a, b) of one window, indices into `scans`: (j, j + s) chained from its start.
std::vector<std::pair<std::size_t, std::size_t>> window_pairs(std::size_t start, std::size_t stride, std::size_t scan_count,
                                                              const OdometryTimeOffsetConfig& config) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t p = 0; p < config.window_pairs; ++p) {
    const std::size_t a = start + p * stride, b = a + stride;
    if (b >= scan_count) break;
    pairs.emplace_back(a, b);
  }
  return pairs;
}

// Step 1 for a log: its laser chain, the scans used, the pair stride and the windows' starts.
struct Windows {
  OdometryChain chain;
  std::vector<std::size_t> scans;  // chain entries
  std::size_t stride = 1;
  std::vector<std::size_t> starts;  // into `scans`
};

Windows plan_windows(const TimeOffsetInput& input, const OdometryTimeOffsetConfig& config) {
  Windows windows;
  windows.chain = input.chain();
  windows.scans = input.scans();
  windows.stride = pair_stride(windows.chain, windows.scans, config.pair_span);
  windows.starts = window_starts(windows.scans.size(), windows.stride, config);
  return windows;
}

// Step 2: the heading pairs of one window, matched along it with a constant-velocity guess.
void match_window(const TimeOffsetInput& input, const Windows& windows, std::size_t start,
                  std::size_t group, const OdometryTimeOffsetConfig& config, std::vector<HeadingPair>& pairs) {
  const OdometryChain& chain = windows.chain;
  const std::vector<std::size_t>& scans = windows.scans;
  const auto scan_at = [&](std::size_t i) -> const LaserScan& { return input.scan(scans[i]); };
  std::optional<SE2> velocity;  // the last accepted motion per second, in the sensor frame
  PointCloud2 target = usable_cloud(scan_at(start), config);
  for (const auto& [a, b] : window_pairs(start, windows.stride, scans.size(), config)) {
    PointCloud2 source = usable_cloud(scan_at(b), config);
    const double dt = chain[scans[b]].stamp - chain[scans[a]].stamp;
    std::optional<SE2> match;
    if (dt > 0.0 && dt <= config.max_pair_dt) {
      if (velocity) {
        const SE2 guess(velocity->x() * dt, velocity->y() * dt, velocity->theta() * dt);
        match = gated_match(target, source, guess, config);
      }
      if (!match) match = gated_match(target, source, SE2(), config);
    }
    if (match) {
      pairs.push_back({scans[a], scans[b], match->theta(), group});
      velocity = SE2(match->x() / dt, match->y() / dt, match->theta() / dt);
    } else {
      velocity.reset();
    }
    target = std::move(source);
  }
}

// Step 3: Eq. (1) summed per jackknife group, on the grid d_k = -max_offset + k grid_step.
struct CostCurves {
  std::vector<double> offsets;              // s, the grid
  std::vector<std::vector<double>> sums;    // [group][k]: sum of rho over the group's pairs
  std::vector<std::size_t> counts;          // pairs per group
};

CostCurves heading_costs(const OdometryChain& chain, const std::vector<HeadingPair>& pairs,
                         std::size_t groups, const OdometryTimeOffsetConfig& config) {
  CostCurves curves;
  const auto steps = static_cast<long>(std::floor(config.max_offset / config.grid_step + 1e-9));
  for (long k = -steps; k <= steps; ++k) curves.offsets.push_back(static_cast<double>(k) * config.grid_step);
  curves.sums.assign(groups, std::vector<double>(curves.offsets.size(), 0.0));
  curves.counts.assign(groups, 0);
  for (const HeadingPair& pair : pairs) {
    ++curves.counts[pair.group];
    std::vector<double>& sum = curves.sums[pair.group];
    for (std::size_t k = 0; k < curves.offsets.size(); ++k) {
      const double d = curves.offsets[k];
      const SE2 a = chain.shifted(pair.first, -d);
      const SE2 b = chain.shifted(pair.second, -d);
      const double residual = angle_difference(pair.turn, angle_difference(b.theta(), a.theta()));
      const double r = residual / config.residual_scale;
      sum[k] += std::log1p(r * r);  // rho, the Cauchy cost
    }
  }
  return curves;
}

// Step 4: the minimum of a cost curve, refined by a parabola; nullopt when it lies on the edge.
std::optional<double> refined_minimum(const std::vector<double>& offsets, const std::vector<double>& cost) {
  const auto best = static_cast<std::size_t>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  if (best == 0 || best + 1 == cost.size()) return std::nullopt;
  const double left = cost[best - 1], middle = cost[best], right = cost[best + 1];
  const double curvature = left - 2.0 * middle + right;
  const double step = offsets[best + 1] - offsets[best];
  const double shift = curvature > 0.0 ? std::clamp(0.5 * (left - right) / curvature, -0.5, 0.5) : 0.0;
  return offsets[best] + shift * step;
}

// The cost over every group but `left_out` (none: all), per pair.
std::vector<double> mean_cost(const CostCurves& curves, std::optional<std::size_t> left_out) {
  std::vector<double> cost(curves.offsets.size(), 0.0);
  std::size_t count = 0;
  for (std::size_t g = 0; g < curves.sums.size(); ++g) {
    if (g == left_out) continue;
    count += curves.counts[g];
    for (std::size_t k = 0; k < cost.size(); ++k) cost[k] += curves.sums[g][k];
  }
  for (double& c : cost) c /= static_cast<double>(std::max<std::size_t>(count, 1));
  return cost;
}

// Step 5: the jackknife standard error of the minimum over the groups left out in turn.
double jackknife_error(const CostCurves& curves) {
  std::vector<double> estimates;
  for (std::size_t g = 0; g < curves.sums.size(); ++g) {
    const std::optional<double> estimate = refined_minimum(curves.offsets, mean_cost(curves, g));
    if (!estimate) return std::numeric_limits<double>::infinity();
    estimates.push_back(*estimate);
  }
  return jackknife_standard_error(estimates);
}

// The cost at the grid's offset nearest to `offset`.
double cost_at(const CostCurves& curves, const std::vector<double>& cost, double offset) {
  const auto nearest = std::min_element(curves.offsets.begin(), curves.offsets.end(),
                                        [&](double a, double b) { return std::abs(a - offset) < std::abs(b - offset); });
  return cost[static_cast<std::size_t>(nearest - curves.offsets.begin())];
}

OdometryTimeOffset estimate(const TimeOffsetInput& input, const OdometryTimeOffsetConfig& config) {
  OdometryTimeOffset result;
  // Step 1: windows of pairs spread over the log, dealt into the jackknife groups.
  const Windows windows = plan_windows(input, config);
  const OdometryChain& chain = windows.chain;
  const std::vector<std::size_t>& scans = windows.scans;
  const std::vector<std::size_t>& starts = windows.starts;
  const std::size_t groups = std::min(config.jackknife_groups, starts.size());
  if (groups < 3) {
    result.reason = "too few scans with odometry (" + std::to_string(scans.size()) + ")";
    return result;
  }
  // Step 2: the heading change of each pair from the scans alone.
  std::vector<HeadingPair> pairs;
  for (std::size_t w = 0; w < starts.size(); ++w) match_window(input, windows, starts[w], w % groups, config, pairs);
  result.pairs = pairs.size();
  if (result.pairs < config.min_turning_pairs) {
    result.reason = "too few scan pairs matched: " + std::to_string(result.pairs) + " (scans more than " +
                    format_number(config.max_pair_dt) + " s apart are not paired)";
    return result;
  }
  for (const HeadingPair& pair : pairs) {
    const double dt = chain[pair.second].stamp - chain[pair.first].stamp;
    if (std::abs(pair.turn) >= config.min_turn_rate * dt) ++result.turning_pairs;
  }
  if (result.turning_pairs < config.min_turning_pairs) {
    result.reason = "too few turns: " + std::to_string(result.turning_pairs) + " turning scan pairs of " +
                    std::to_string(result.pairs) + " matched, at least " + std::to_string(config.min_turning_pairs) + " needed";
    return result;
  }
  // Steps 3 and 4: Eq. (1) over the grid, its refined minimum.
  const CostCurves curves = heading_costs(chain, pairs, groups, config);
  const std::vector<double> cost = mean_cost(curves, std::nullopt);
  result.cost_at_zero = cost_at(curves, cost, 0.0);
  const std::optional<double> best = refined_minimum(curves.offsets, cost);
  if (!best) {
    result.reason = "the cost is least at the edge of the search (+-" + format_number(config.max_offset) + " s)";
    return result;
  }
  result.best = *best;
  result.cost_at_best = cost_at(curves, cost, *best);
  // Step 5: how well the windows agree.
  result.uncertainty = jackknife_error(curves);
  if (!(result.uncertainty <= config.max_uncertainty)) {
    result.reason = "uncertain: " + format_number(std::round(result.uncertainty * 1000.0) / 1000.0) + " s (jackknife) above " +
                    format_number(config.max_uncertainty) + " s";
    return result;
  }
  result.estimated = true;
  result.offset = *best;
  result.significant = std::abs(*best) >= config.min_significant_offset;
  return result;
}

// The whole log read, every scan kept or none.
TimeOffsetInput input_of(const std::vector<SensorMessage>& messages, bool with_scans) {
  TimeOffsetInput input;
  for (const SensorMessage& message : messages) input.add(message, with_scans);
  return input;
}

}  // namespace

void TimeOffsetInput::add(const SensorMessage& message, bool with_scan) {
  const std::optional<ChainSample> sample = chain_sample(messages_++, message);
  if (!sample) return;
  const std::size_t entry = samples_.size();
  samples_.push_back(*sample);
  const auto* laser = std::get_if<LaserMessage>(&message);
  if (laser == nullptr) return;
  if (!type_) type_ = laser->type;
  if (laser->type != *type_) return;
  scans_.push_back(entry);
  if (with_scan) kept_.emplace_back(entry, laser->scan);
}

bool TimeOffsetInput::set_scan(std::size_t index, LaserScan scan) {
  const auto sample = std::lower_bound(samples_.begin(), samples_.end(), index,
                                       [](const ChainSample& s, std::size_t i) { return s.message < i; });
  const auto entry = static_cast<std::size_t>(sample - samples_.begin());
  if (sample == samples_.end() || sample->message != index || sample->stamp != scan.stamp ||
      !std::binary_search(scans_.begin(), scans_.end(), entry)) {
    return false;
  }
  const auto at = std::lower_bound(kept_.begin(), kept_.end(), entry, [](const auto& kept, std::size_t e) { return kept.first < e; });
  if (at != kept_.end() && at->first == entry) {
    at->second = std::move(scan);
  } else {
    kept_.emplace(at, entry, std::move(scan));
  }
  return true;
}

const LaserScan& TimeOffsetInput::scan(std::size_t k) const {
  static const LaserScan kNone{};
  const auto at = std::lower_bound(kept_.begin(), kept_.end(), k, [](const auto& kept, std::size_t e) { return kept.first < e; });
  return at != kept_.end() && at->first == k ? at->second : kNone;
}

std::vector<std::size_t> odometry_time_offset_scans(const TimeOffsetInput& input, const OdometryTimeOffsetConfig& config) {
  validate(config);
  const Windows windows = plan_windows(input, config);
  std::vector<std::size_t> used;
  for (const std::size_t start : windows.starts) {
    for (const auto& [a, b] : window_pairs(start, windows.stride, windows.scans.size(), config)) {
      used.push_back(windows.chain[windows.scans[a]].message);
      used.push_back(windows.chain[windows.scans[b]].message);
    }
  }
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  return used;
}

std::vector<std::size_t> odometry_time_offset_scans(const std::vector<SensorMessage>& messages,
                                                    const OdometryTimeOffsetConfig& config) {
  return odometry_time_offset_scans(input_of(messages, /*with_scans=*/false), config);
}

OdometryTimeOffset estimate_odometry_time_offset(const TimeOffsetInput& input, const OdometryTimeOffsetConfig& config) {
  validate(config);
  const auto start = std::chrono::steady_clock::now();
  OdometryTimeOffset result = estimate(input, config);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

OdometryTimeOffset estimate_odometry_time_offset(const std::vector<SensorMessage>& messages,
                                                 const OdometryTimeOffsetConfig& config) {
  return estimate_odometry_time_offset(input_of(messages, /*with_scans=*/true), config);
}

}  // namespace slam2d
