// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/global_search.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

// Centres of the free map cells on a stride of `stride` cells (the middle cell of each block).
std::vector<Eigen::Vector2d> free_positions(const OccupancyMap& map, int stride) {
  std::vector<Eigen::Vector2d> positions;
  for (int iy = stride / 2; iy < map.height; iy += stride) {
    for (int ix = stride / 2; ix < map.width; ix += stride) {
      const std::int8_t cell = map.at(ix, iy);
      if (cell >= 0 && cell < 50) positions.push_back(map.cell_center(ix, iy));
    }
  }
  return positions;
}

}  // namespace

void validate(const GlobalSearchConfig& config) { check_fields(config, "GlobalSearchConfig"); }

GlobalPoseSearch::GlobalPoseSearch(const LocalizationMap& map, const GlobalSearchConfig& config)
    : config_((validate(config), config)),
      field_map_(map.map(), with_sigma_hit(map.field().config(), std::max(config.sigma_hit, config.step_xy))) {
  const OccupancyMap& m = map.map();
  headings_ = static_cast<int>(std::ceil(2.0 * std::numbers::pi / config_.step_theta - 1e-9));
  heading_step_ = 2.0 * std::numbers::pi / headings_;
  // The finest stride within the budget: the free area shrinks as stride^2.
  int stride = std::max(1, static_cast<int>(std::lround(config_.step_xy / m.resolution)));
  positions_ = free_positions(m, stride);
  while (positions_.size() * static_cast<std::size_t>(headings_) > config_.max_poses && positions_.size() > 1) {
    const double over = static_cast<double>(positions_.size() * static_cast<std::size_t>(headings_)) /
                        static_cast<double>(config_.max_poses);
    stride = std::max(stride + 1, static_cast<int>(std::ceil(stride * std::sqrt(over))));
    positions_ = free_positions(m, stride);
  }
  check(!positions_.empty(), "global search: no free cell on the search grid");
  step_xy_ = stride * m.resolution;
}

void GlobalPoseSearch::restart() {
  hypotheses_.clear();
  scores_.clear();
  grid_index_.clear();
  T_start_robot_ = SE2();
  scans_ = 0;
}

SE2 GlobalPoseSearch::grid_pose(std::size_t index) const {
  const std::size_t h = static_cast<std::size_t>(headings_);
  return SE2(positions_[index / h], -std::numbers::pi + static_cast<double>(index % h) * heading_step_);
}

void GlobalPoseSearch::score_grid(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_start_robot) {
  const std::size_t total = grid_poses();
  std::vector<float> scores(total);
  std::vector<SE2> poses;
  std::vector<double> log_likelihoods;
  constexpr std::size_t kBlock = 1024;
  for (std::size_t begin = 0; begin < total; begin += kBlock) {
    const std::size_t end = std::min(total, begin + kBlock);
    poses.clear();
    for (std::size_t i = begin; i < end; ++i) poses.push_back(grid_pose(i) * T_start_robot);
    field_map_.scan_log_likelihoods(points_robot, poses, log_likelihoods);
    for (std::size_t i = begin; i < end; ++i) scores[i] = static_cast<float>(log_likelihoods[i - begin]);
  }
  // The best `keep`, best first, ties by grid index.
  std::vector<std::uint32_t> order(total);
  std::iota(order.begin(), order.end(), 0u);
  const auto better = [&](std::uint32_t a, std::uint32_t b) { return scores[a] > scores[b] || (scores[a] == scores[b] && a < b); };
  const std::size_t kept = std::min(config_.keep, total);
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(kept - 1), order.end(), better);
  order.resize(kept);
  std::sort(order.begin(), order.end());  // grid order: deterministic, and the later passes read the table in order
  grid_index_ = order;
  hypotheses_.resize(kept);
  scores_.resize(kept);
  for (std::size_t k = 0; k < kept; ++k) {
    hypotheses_[k] = grid_pose(order[k]);
    scores_[k] = scores[order[k]];
  }
}

void GlobalPoseSearch::add_scan(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_start_robot) {
  T_start_robot_ = T_start_robot;
  if (scans_ == 0) {
    score_grid(points_robot, T_start_robot);
  } else {
    std::vector<SE2> poses(hypotheses_.size());
    for (std::size_t k = 0; k < hypotheses_.size(); ++k) poses[k] = hypotheses_[k] * T_start_robot;
    std::vector<double> log_likelihoods;
    field_map_.scan_log_likelihoods(points_robot, poses, log_likelihoods);
    for (std::size_t k = 0; k < hypotheses_.size(); ++k) scores_[k] += log_likelihoods[k];
  }
  ++scans_;
}

std::vector<std::size_t> GlobalPoseSearch::ranking() const {
  std::vector<std::size_t> order(hypotheses_.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return scores_[a] > scores_[b] || (scores_[a] == scores_[b] && grid_index_[a] < grid_index_[b]);
  });
  return order;
}

SE2 GlobalPoseSearch::jittered(std::size_t hypothesis, Rng& rng) const {
  const SE2& h = hypotheses_[hypothesis];
  const double half_xy = 0.5 * step_xy_;
  const double half_theta = 0.5 * heading_step_;
  const double dx = rng.uniform(-half_xy, half_xy);  // drawn in a fixed order: same seed, same poses
  const double dy = rng.uniform(-half_xy, half_xy);
  const double dtheta = rng.uniform(-half_theta, half_theta);
  return SE2(h.x() + dx, h.y() + dy, h.theta() + dtheta) * T_start_robot_;
}

std::vector<std::vector<SE2>> GlobalPoseSearch::seed_places(std::size_t count, std::size_t max_places,
                                                            std::size_t particles, double radius_xy,
                                                            double radius_theta, Rng& rng) const {
  check(!hypotheses_.empty(), "global search: seed_places() before any scan");
  const std::vector<std::size_t> order = ranking();
  std::vector<std::vector<std::size_t>> members;  // hypothesis indices per place, best first
  std::vector<SE2> centres;                       // each place's best hypothesis
  for (std::size_t r = 0; r < std::min(count, order.size()); ++r) {
    const SE2 h = hypotheses_[order[r]] * T_start_robot_;
    std::size_t place = 0;
    while (place < centres.size() && ((h.translation() - centres[place].translation()).norm() > radius_xy ||
                                      std::abs(angle_difference(h.theta(), centres[place].theta())) > radius_theta)) {
      ++place;
    }
    if (place == centres.size()) {
      if (centres.size() == max_places) continue;
      centres.push_back(h);
      members.emplace_back();
    }
    members[place].push_back(order[r]);
  }
  std::vector<std::vector<SE2>> places(members.size());
  const std::size_t particles_per_place = std::max<std::size_t>(1, particles / members.size());
  for (std::size_t p = 0; p < members.size(); ++p) {
    places[p].reserve(particles_per_place);
    for (std::size_t i = 0; i < particles_per_place; ++i) places[p].push_back(jittered(members[p][i % members[p].size()], rng));
  }
  return places;
}

SE2 GlobalPoseSearch::best() const {
  check(!hypotheses_.empty(), "global search: best() before any scan");
  return hypotheses_[ranking().front()] * T_start_robot_;
}

void GlobalPoseSearch::spread(std::size_t count, SE2* mean, Covariance3* covariance) const {
  check(!hypotheses_.empty(), "global search: spread() before any scan");
  const std::vector<std::size_t> order = ranking();
  const std::size_t n = std::clamp<std::size_t>(count, 1, order.size());
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  double c = 0.0;
  double s = 0.0;
  std::vector<SE2> poses(n);
  for (std::size_t i = 0; i < n; ++i) {
    poses[i] = hypotheses_[order[i]] * T_start_robot_;
    t += poses[i].translation();
    c += std::cos(poses[i].theta());
    s += std::sin(poses[i].theta());
  }
  t /= static_cast<double>(n);
  const double theta = std::atan2(s, c);
  Covariance3 cov = Covariance3::Zero();
  for (const SE2& p : poses) {
    const Eigen::Vector3d d(p.x() - t.x(), p.y() - t.y(), angle_difference(p.theta(), theta));
    cov += d * d.transpose();
  }
  *mean = SE2(t, theta);
  *covariance = cov / static_cast<double>(n);
}

}  // namespace slam2d
