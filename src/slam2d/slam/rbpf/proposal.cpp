// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/rbpf/proposal.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/grid/bilinear.hpp"
#include "slam2d/registration/degeneracy.hpp"

namespace slam2d {

namespace {

// The tangent coordinates of x in the frame of `origin`: (x, y) of origin^-1 x and its angle.
Eigen::Vector3d local_coordinates(const SE2& origin, const SE2& x) {
  const SE2 d = origin.between(x);
  return {d.x(), d.y(), normalize_angle(d.theta())};
}

SE2 from_local(const SE2& origin, const Eigen::Vector3d& v) { return origin * SE2(v.x(), v.y(), v.z()); }

// The occupancy probability 1 / (1 + exp(-l)) of a cell (0.5 if never observed), from a table
// over l in [-kRange, kRange] with linear interpolation (error below 1e-6), exact outside.
class LogisticTable {
 public:
  static constexpr double kRange = 12.0;
  static constexpr int kSteps = 6144;
  LogisticTable() {
    for (int k = 0; k <= kSteps + 1; ++k) {
      const double l = -kRange + k * (2.0 * kRange / kSteps);
      values_[static_cast<std::size_t>(k)] = 1.0 / (1.0 + std::exp(-l));
    }
  }
  inline double operator()(double l) const {
    const double x = (l + kRange) * (kSteps / (2.0 * kRange));
    if (!(x >= 0.0 && x < kSteps)) return 1.0 / (1.0 + std::exp(-l));
    const auto k = static_cast<std::size_t>(x);
    const double f = x - static_cast<double>(k);
    return values_[k] + f * (values_[k + 1] - values_[k]);
  }

 private:
  std::array<double, kSteps + 2> values_{};
};

const LogisticTable kLogistic;

}  // namespace

void validate(const RbpfMotionNoise& noise) {
  check_fields(noise, "RbpfMotionNoise");
  check(noise.max_sigma_translation >= noise.min_sigma_translation && noise.max_sigma_rotation >= noise.min_sigma_rotation,
        "RbpfMotionNoise: max_sigma_translation and max_sigma_rotation must be at least their floors");
}

void validate(const RbpfProposalConfig& config) {
  check_fields(config, "RbpfProposalConfig");
  validate(config.matcher);
}

Eigen::Vector3d motion_sigmas(const SE2& u, const RbpfMotionNoise& noise) {
  const double d = u.translation().norm();
  const double a = std::abs(normalize_angle(u.theta()));
  const double sigma_t = std::max(noise.min_sigma_translation, noise.srr * d + noise.srt * a);
  const double sigma_r = std::max(noise.min_sigma_rotation, noise.str * d + noise.stt * a);
  return {sigma_t, sigma_t, sigma_r};
}

Eigen::Vector3d update_sigmas(const SE2& u, const RbpfMotionNoise& noise) {
  const Eigen::Vector3d caps(noise.max_sigma_translation, noise.max_sigma_translation, noise.max_sigma_rotation);
  return motion_sigmas(u, noise).cwiseMin(caps);
}

double log_motion_density(const SE2& x, const SE2& predicted, const Eigen::Vector3d& sigmas) {
  const Eigen::Vector3d e = local_coordinates(predicted, x).cwiseQuotient(sigmas);
  const double log_norm = -1.5 * std::log(2.0 * std::numbers::pi) - std::log(sigmas.prod());
  return log_norm - 0.5 * e.squaredNorm();
}

double log_observation_likelihood(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points_robot,
                                  const SE2& T_map_robot, double sigma, std::size_t stride) {
  check(stride >= 1, "log_observation_likelihood: stride must be >= 1");
  const double c = std::cos(T_map_robot.theta());
  const double s = std::sin(T_map_robot.theta());
  const Eigen::Vector2d& t = T_map_robot.translation();
  // The same value as interpolate_occupancy (grid/bilinear.hpp), without its gradient and with the
  // logistic function read from a table: this loop is most of the filter's time.
  const GridGeometry& geometry = grid.geometry();
  const double inverse_resolution = 1.0 / geometry.resolution;
  // Same values as below, computed faster (the results are bit for bit those of the plain code):
  //  - in_index_range(S, limit) divides by the resolution; an offset of at most half the limit in
  //    cells passes it surely, so the division is done only beyond that (never in practice);
  //  - the last tile looked up is remembered;
  //  - the table's logistic function is read through an exact memo (FloatMemo, bilinear.hpp):
  //    the cells hold few distinct log-odds values.
  constexpr double kLimit = GridGeometry::kMaxCellIndex - 2.0;
  const double sure_offset = 0.5 * kLimit * geometry.resolution;
  const auto logistic = [](float l) { return kLogistic(l); };
  thread_local FloatMemo<9> memo(logistic);  // this thread's
  // 0.5 for unknown cells, else the table at the log-odds: an unknown cell holds the default
  // log-odds +0 (OccupancyGrid stamps last_scan >= 1 at every write) and the table reads exactly
  // 0.5 there (its sample 3072 at l = 0, fraction 0), so the memo alone gives both cases.
  const auto probability = [&](const OccupancyCell& cell) { return memo(cell.log_odds, logistic); };
  CornerReader corners(grid);
  double sum = 0.0;
  std::size_t used = 0;
  for (std::size_t k = 0; k < points_robot.size(); k += stride, ++used) {
    const Eigen::Vector2d& p = points_robot[k];
    const Eigen::Vector2d S(c * p.x() - s * p.y() + t.x(), s * p.x() + c * p.y() + t.y());
    double value = 0.5;
    const double dx = S.x() - geometry.origin.x();
    const double dy = S.y() - geometry.origin.y();
    if ((std::abs(dx) <= sure_offset && std::abs(dy) <= sure_offset) || geometry.in_index_range(S, kLimit)) {
      const double u = dx * inverse_resolution - 0.5;
      const double v = dy * inverse_resolution - 0.5;
      const CellIndex i{GridGeometry::floor_to_int(u), GridGeometry::floor_to_int(v)};
      const double fx = u - i.x;
      const double fy = v - i.y;
      const auto [m00, m10, m01, m11] = corners(i, probability);  // 0.5 for unknown cells
      value = bilinear_value(m00, m10, m01, m11, fx, fy);
    }
    const double r = 1.0 - value;
    sum += r * r;
  }
  // Every stride-th end point stands for the stride points around it (same scale as stride 1).
  const double scale = used > 0 ? static_cast<double>(points_robot.size()) / static_cast<double>(used) : 0.0;
  return -scale * sum / (2.0 * sigma * sigma);
}

ProposalResult improved_proposal(const MapPyramid& map, const std::vector<Eigen::Vector2d>& points_robot,
                                 const SE2& predicted, const Eigen::Vector3d& sigmas, const RbpfProposalConfig& config,
                                 bool fit) {
  ProposalResult result;
  result.x_star = predicted;
  if (map.level(0).scan_count() == 0 || points_robot.size() < config.min_points) return result;
  // x* = argmax p(z | m, x), from x'.
  // The matcher maximises p(z | m, x) p(x | x_{t-1}, u) (the proposal's mode): the motion model
  // enters as a Gaussian prior in Hector's cost units (cost = 0.5 sum r^2 = sigma^2 (-log L)),
  // so it only decides the directions the scan leaves open (a corridor's axis).
  const double c = std::cos(predicted.theta());
  const double s = std::sin(predicted.theta());
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  R.topLeftCorner<2, 2>() << c, -s, s, c;
  const Eigen::Vector3d inverse_variances = sigmas.cwiseProduct(sigmas).cwiseInverse();
  const PosePrior prior{.mean = predicted,
                        .information = config.motion_prior_weight * config.likelihood_sigma * config.likelihood_sigma *
                                       R * inverse_variances.asDiagonal() * R.transpose(),
                        .kernel = config.motion_prior_kernel};
  const MatchResult match = match_scan_to_pyramid(map, points_robot, predicted, config.matcher,
                                                  config.motion_prior_weight > 0.0 ? std::optional(prior) : std::nullopt);
  const Eigen::Vector3d correction = local_coordinates(predicted, match.T_target_source);
  if (match.degenerate || mean_squared_residual(match) > config.max_match_residual ||
      correction.head<2>().norm() > config.max_match_translation || std::abs(correction.z()) > config.max_match_rotation) {
    return result;
  }
  result.x_star = match.T_target_source;
  result.match_covariance = match.covariance;
  if (!fit) {
    result.matched = true;
    return result;
  }
  // tau_j at the grid of poses around x*, Eq. (14)-(15); weights relative to the largest. Along
  // the translation the scan's geometry leaves open (a featureless corridor's axis) the map's
  // likelihood is not the scan's evidence: a map built from a few viewpoints holds the corridor's
  // far walls as dots, whose pull varies along the axis and, fitted here at each update, draws the
  // mean back towards the last viewpoint (the hospital world: 0.46 m lost over 13 m). There the
  // likelihood is read with that part of x_j removed, and the fit keeps x*'s (the prediction's).
  const std::optional<Eigen::Vector2d> open = scan_open_translation(points_robot, config.matcher);
  const auto observed = [&](const Eigen::Vector3d& vj) {
    return from_local(result.x_star, open ? without_translation_along(vj, *open) : vj);
  };
  const int k = config.sample_radius;
  const int side = 2 * k + 1;
  std::vector<Eigen::Vector3d> v;
  std::vector<double> log_tau;
  v.reserve(static_cast<std::size_t>(side * side * side));
  log_tau.reserve(v.capacity());
  const OccupancyGrid& grid = map.level(0);
  for (int ix = -k; ix <= k; ++ix) {
    for (int iy = -k; iy <= k; ++iy) {
      for (int it = -k; it <= k; ++it) {
        const Eigen::Vector3d vj(ix * config.sample_step_translation, iy * config.sample_step_translation,
                                 it * config.sample_step_rotation);
        const SE2 xj = from_local(result.x_star, vj);
        v.push_back(vj);
        log_tau.push_back(log_observation_likelihood(grid, points_robot, observed(vj), config.likelihood_sigma,
                                                     config.likelihood_stride) +
                          log_motion_density(xj, predicted, sigmas));
      }
    }
  }
  double max_log = log_tau.front();
  for (const double l : log_tau) max_log = std::max(max_log, l);
  double eta = 0.0;  // Eq. (18), scaled by exp(-max_log)
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < v.size(); ++j) {
    const double tau = std::exp(log_tau[j] - max_log);
    eta += tau;
    mean += tau * v[j];  // Eq. (16)
  }
  mean /= eta;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < v.size(); ++j) {
    const Eigen::Vector3d d = v[j] - mean;
    covariance += std::exp(log_tau[j] - max_log) * d * d.transpose();  // Eq. (17)
  }
  covariance /= eta;
  if (open) {  // the prediction stands along the open axis, as in the match
    const Eigen::Vector3d w(open->x(), open->y(), 0.0);
    const Eigen::Matrix3d keep = Eigen::Matrix3d::Identity() - w * w.transpose();
    mean = keep * mean;
    covariance = keep * covariance * keep;
  }
  // Floor: a peaked likelihood puts all the mass on one grid pose; its spread is then below the
  // grid step, not zero.
  const double floor_t = config.sample_step_translation / std::sqrt(12.0);
  const double floor_r = config.sample_step_rotation / std::sqrt(12.0);
  covariance.diagonal() += Eigen::Vector3d(floor_t * floor_t, floor_t * floor_t, floor_r * floor_r) * 0.25;
  const double cell_volume =
      config.sample_step_translation * config.sample_step_translation * config.sample_step_rotation;
  result.mean = mean;
  result.covariance = covariance;
  result.log_normalizer = max_log + std::log(eta * cell_volume);
  result.matched = true;
  return result;
}

SE2 proposal_mean(const ProposalResult& proposal, const SE2& predicted) {
  return proposal.matched ? from_local(proposal.x_star, proposal.mean) : predicted;
}

SE2 sample_pose(const ProposalResult& proposal, const MapPyramid& map, const std::vector<Eigen::Vector2d>& points_robot,
                const SE2& predicted, const Eigen::Vector3d& sigmas, const RbpfProposalConfig& config, Rng& rng,
                double& log_weight_factor) {
  const Eigen::Vector3d n(rng.gaussian(), rng.gaussian(), rng.gaussian());
  if (proposal.matched) {
    const Eigen::Matrix3d L = proposal.covariance.llt().matrixL();
    log_weight_factor = config.weight_gain * proposal.log_normalizer;
    return from_local(proposal.x_star, proposal.mean + L * n);
  }
  // Fallback: the motion model p(x | x_{t-1}, u); weight p(z | m, x) (0 before the first scan).
  const SE2 x = from_local(predicted, sigmas.cwiseProduct(n));
  log_weight_factor = map.level(0).scan_count() == 0
                          ? 0.0
                          : config.weight_gain *
                                log_observation_likelihood(map.level(0), points_robot, x, config.likelihood_sigma, config.likelihood_stride);
  return x;
}

}  // namespace slam2d
