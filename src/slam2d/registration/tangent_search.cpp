// SPDX-License-Identifier: BSD-3-Clause
// The tangent-based rotation search and least-squares matcher (F. Lu and E. Milios, J. Intelligent
// and Robotic Systems 18, 1997, Sec. 3). Equation numbers refer to tangent_search.hpp.

#include "slam2d/registration/tangent_search.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/covariance.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr std::size_t kCandidates = 8;  // nearest target points tried for a compatible tangent

PointCloud2 with_tangents(const PointCloud2& cloud, const TangentSearchConfig& config) {
  PointCloud2 out;
  out.points = cloud.points;
  estimate_normals_ordered(out, NormalEstimationConfig{.neighbors = config.tangent_neighbors,
                                                       .max_neighbor_distance = config.tangent_max_distance,
                                                       .min_neighbors = 3});
  return out;
}

// The direction of a normal's tangent line, modulo pi, in [0, pi).
double tangent_angle(const Point2& normal) {
  const double a = std::atan2(normal.y(), normal.x()) + kPi / 2.0;
  return a - kPi * std::floor(a / kPi);
}

// |a - b| modulo pi, in [0, pi/2].
double line_angle_difference(double a, double b) {
  const double d = std::abs(std::remainder(a - b, kPi));
  return std::min(d, kPi - d);
}

// The Gaussian-smoothed histogram of the tangent directions turned by `rotation`, over [0, pi).
std::vector<double> tangent_histogram(const PointCloud2& cloud, double rotation, const TangentSearchConfig& config) {
  const int bins = config.histogram_bins;
  const double width = kPi / bins;
  const int reach = static_cast<int>(std::ceil(3.0 * config.histogram_sigma / width));
  std::vector<double> histogram(static_cast<std::size_t>(bins), 0.0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!has_normal(cloud, i)) continue;
    const double position = (tangent_angle(cloud.normals[i]) + rotation) / width;  // in bins, unwrapped
    const int center = static_cast<int>(std::floor(position));
    for (int b = center - reach; b <= center + reach; ++b) {
      const double offset = (b + 0.5 - position) * width / config.histogram_sigma;
      histogram[static_cast<std::size_t>(((b % bins) + bins) % bins)] += std::exp(-0.5 * offset * offset);
    }
  }
  return histogram;
}

double circular_correlation(const std::vector<double>& a, const std::vector<double>& b, int shift) {
  const int n = static_cast<int>(a.size());
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += a[static_cast<std::size_t>(k)] * b[static_cast<std::size_t>(((k - shift) % n + n) % n)];
  return sum;
}

// ---- Eq. (2)-(4): least squares with the tangent lines ----

struct TangentPairs {
  std::vector<Point2> source;   // p_i, source frame
  std::vector<Point2> target;   // q_i
  std::vector<Point2> normals;  // n_i, the target's tangent-line normal at q_i
  std::vector<Correspondence> correspondences;
  std::size_t size() const { return source.size(); }
};

TangentPairs pair_points(const PointCloud2& target, const KdTree2& tree, const PointCloud2& source, const SE2& T,
                         double max_distance, double max_tangent_difference) {
  TangentPairs pairs;
  std::vector<Neighbor> neighbors;
  const double max_squared = max_distance * max_distance;
  for (std::size_t i = 0; i < source.size(); ++i) {
    if (!has_normal(source, i)) continue;
    const double turned = tangent_angle(T.rotation() * source.normals[i]);
    tree.nearest_k(T * source.points[i], kCandidates, neighbors);
    for (const Neighbor& neighbor : neighbors) {
      if (neighbor.squared_distance > max_squared) break;
      const std::size_t j = neighbor.index;
      if (!has_normal(target, j) || line_angle_difference(tangent_angle(target.normals[j]), turned) > max_tangent_difference) {
        continue;
      }
      pairs.source.push_back(source.points[i]);
      pairs.target.push_back(target.points[j]);
      pairs.normals.push_back(target.normals[j]);
      pairs.correspondences.push_back({i, j, kNoPoint, 1.0});
      break;
    }
  }
  return pairs;
}

// Eq. (3): t(w) minimising Eq. (2), as a step from `t` damped by a trace-relative 1e-9 (a corridor
// leaves one direction free: it stays where it was); returns E(w, t(w)) through `cost`.
Point2 translation_for(const TangentPairs& pairs, double w, const Point2& t, double& cost) {
  const Eigen::Matrix2d R = SE2(0.0, 0.0, w).rotation();
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Point2 b = Point2::Zero();
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const Point2& n = pairs.normals[i];
    A += n * n.transpose();
    b += n * n.dot(pairs.target[i] - R * pairs.source[i] - t);
  }
  A += (1e-9 * A.trace() + 1e-12) * Eigen::Matrix2d::Identity();
  const Point2 solution = t + A.ldlt().solve(b);
  cost = 0.0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const double r = pairs.normals[i].dot(R * pairs.source[i] + solution - pairs.target[i]);
    cost += r * r;
  }
  return solution;
}

// Eq. (4): golden-section search of E(w, t(w)) over [w - width, w + width].
SE2 rotation_search(const TangentPairs& pairs, const SE2& T, double width) {
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double low = T.theta() - width;
  double high = T.theta() + width;
  const auto cost_at = [&](double w) {
    double cost = 0.0;
    translation_for(pairs, w, T.translation(), cost);
    return cost;
  };
  double a = high - ratio * (high - low);
  double b = low + ratio * (high - low);
  double cost_a = cost_at(a);
  double cost_b = cost_at(b);
  while (high - low > 1e-7) {
    if (cost_a <= cost_b) {
      high = b, b = a, cost_b = cost_a;
      a = high - ratio * (high - low), cost_a = cost_at(a);
    } else {
      low = a, a = b, cost_a = cost_b;
      b = low + ratio * (high - low), cost_b = cost_at(b);
    }
  }
  const double w = 0.5 * (low + high);
  double cost = 0.0;
  return SE2(translation_for(pairs, w, T.translation(), cost), w);
}

// Fills inliers, residual, covariance and the degeneracy verdict from the final pairs.
void finish(const PointCloud2& target, const PointCloud2& source, const TangentPairs& pairs,
            const TangentSearchConfig& config, MatchResult& result) {
  const SE2& T = result.T_target_source;
  result.inliers = pairs.size();
  result.residual = rms_residual(target, source, T, pairs.correspondences, ErrorMetric::kPointToLine);
  result.covariance = censi_covariance(target, source, T, pairs.correspondences, ErrorMetric::kPointToLine,
                                       SensorNoise{.range_sigma = config.range_sigma});
  apply(analyze_degeneracy(target, source, T, pairs.correspondences, DegeneracyConfig{.range_sigma = config.range_sigma}),
        result);
  if (result.inliers < static_cast<std::size_t>(config.min_correspondences)) result.converged = false;
}

}  // namespace

void validate(const TangentSearchConfig& c) {
  check_fields(c, "TangentSearchConfig");
  check(c.max_distance_final <= c.max_distance_initial, "TangentSearchConfig: max_distance_final must be <= max_distance_initial");
}

double tangent_histogram_rotation(const PointCloud2& target, const PointCloud2& source, double guess_rotation,
                                  const TangentSearchConfig& config) {
  validate(config);
  const std::vector<double> h_target = tangent_histogram(target, 0.0, config);
  const std::vector<double> h_source = tangent_histogram(source, guess_rotation, config);
  const double width = kPi / config.histogram_bins;
  const int reach = std::min(static_cast<int>(std::floor(config.max_rotation / width)), config.histogram_bins / 2 - 1);
  int best = 0;
  double best_score = -1.0;
  for (int shift = -reach; shift <= reach; ++shift) {  // Eq. (1)
    const double score = circular_correlation(h_target, h_source, shift);
    if (score > best_score) best = shift, best_score = score;
  }
  double offset = 0.0;  // the parabola through the peak and its neighbours, in bins
  if (best > -reach && best < reach) {
    const double left = circular_correlation(h_target, h_source, best - 1);
    const double right = circular_correlation(h_target, h_source, best + 1);
    const double curvature = left - 2.0 * best_score + right;
    if (curvature < 0.0) offset = std::clamp(0.5 * (left - right) / curvature, -0.5, 0.5);
  }
  return guess_rotation + (best + offset) * width;
}

MatchResult match_tangent_search(const PointCloud2& target, const PointCloud2& source,
                                 const SE2& T_target_source_guess, const TangentSearchConfig& config) {
  validate(config);
  const auto min_pairs = static_cast<std::size_t>(config.min_correspondences);
  if (target.size() < min_pairs || source.size() < min_pairs) return unmatched(T_target_source_guess, 0);
  const PointCloud2 target_tangents = with_tangents(target, config);
  const PointCloud2 source_tangents = with_tangents(source, config);
  const KdTree2 tree(target_tangents.points);
  SE2 T(T_target_source_guess.translation(),
        tangent_histogram_rotation(target_tangents, source_tangents, T_target_source_guess.theta(), config));  // Eq. (1)
  MatchResult result;
  TangentPairs pairs;
  PoseCycle cycle(2);  // a return to a pose of the last two iterations is a cycle of the pairs: the end
  for (int k = 0; k < config.max_iterations; ++k) {
    const double max_distance = std::max(config.max_distance_final,
                                         config.max_distance_initial * std::exp(-config.max_distance_decay * k));
    pairs = pair_points(target_tangents, tree, source_tangents, T, max_distance, config.max_tangent_difference);
    if (pairs.size() < min_pairs) return unmatched(T_target_source_guess, k + 1);
    const SE2 next = rotation_search(pairs, T, config.rotation_search_width);  // Eq. (2)-(4)
    result.iterations = k + 1;
    const bool settled = max_distance == config.max_distance_final;
    const bool returned = cycle.returned_to(next, config.translation_tolerance, config.rotation_tolerance);
    result.converged =
        settled && (step_below(T, next, config.translation_tolerance, config.rotation_tolerance) || returned);
    T = next;
    if (result.converged) break;
  }
  result.T_target_source = T;
  pairs = pair_points(target_tangents, tree, source_tangents, T, config.max_distance_final,
                      config.max_tangent_difference);
  finish(target_tangents, source, pairs, config, result);
  return result;
}

}  // namespace slam2d
