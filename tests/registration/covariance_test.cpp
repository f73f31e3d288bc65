// SPDX-License-Identifier: BSD-3-Clause
// Censi's closed-form ICP covariance against the Monte-Carlo spread of the estimate: the
// normalised estimation error squared (NEES) over many noisy trials lies within the chi-square
// bounds for three degrees of freedom.

#include "slam2d/registration/covariance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "scan_pair_fixture.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/optim/normal_equations.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {
namespace {

constexpr int kTrials = 300;
// Two-sided 99% bounds of the mean of kTrials chi-square(3) draws: chi2(0.005 / 0.995, 3 kTrials) / kTrials.
constexpr double kNeesLow = 2.59;
constexpr double kNeesHigh = 3.44;

Point2 perpendicular(const Point2& v) { return {-v.y(), v.x()}; }

// Gauss-Newton over the fixed correspondences: the estimator whose spread Censi predicts.
SE2 minimize(const PointCloud2& target, const PointCloud2& source, const std::vector<Correspondence>& pairs,
             ErrorMetric metric, SE2 T) {
  for (int iteration = 0; iteration < 20; ++iteration) {
    NormalEquations<3> equations;
    for (const Correspondence& c : pairs) {
      const Point2 Rp = T.rotation() * source.points[c.source];
      const Point2 error = Rp + T.translation() - target.points[c.target];
      Eigen::Matrix<double, 2, 3> J;
      J << 1.0, 0.0, -Rp.y(), 0.0, 1.0, Rp.x();
      if (metric == ErrorMetric::kPointToPoint) {
        equations.add<2>(J, error);
      } else {
        const Point2 d = target.points[c.target2] - target.points[c.target];
        const Point2 n = perpendicular(d).normalized();
        equations.add(n.transpose() * J, n.dot(error));
      }
    }
    const auto dx = solve_step(equations);
    if (!dx) break;
    T = SE2(T.x() + dx->x(), T.y() + dx->y(), T.theta() + dx->z());
    if (dx->norm() < 1e-12) break;
  }
  return T;
}

double nees(const SE2& estimate, const SE2& truth, const Covariance3& covariance) {
  const Eigen::Vector3d e(estimate.x() - truth.x(), estimate.y() - truth.y(),
                          std::remainder(estimate.theta() - truth.theta(), 2.0 * std::numbers::pi));
  return e.dot(covariance.ldlt().solve(e));
}

TEST(CensiCovariance, PointToPointMatchesMonteCarloSpread) {
  // Exact correspondences: the same wall points seen from two poses, each range with noise.
  const SE2 truth(0.3, -0.2, 0.1);
  Rng rng(3);
  PointCloud2 walls;
  for (int i = 0; i < 120; ++i) walls.points.emplace_back(rng.uniform(-6.0, 6.0), rng.uniform(2.0, 8.0));
  const double sigma = 0.02;
  std::vector<Correspondence> pairs;
  for (std::size_t i = 0; i < walls.size(); ++i) pairs.push_back({.source = i, .target = i});
  double sum = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    PointCloud2 target;
    PointCloud2 source;
    for (const Point2& q : walls.points) {
      const Point2 p = truth.inverse() * q;
      target.points.push_back(q + rng.gaussian(0.0, sigma) * q.normalized());
      source.points.push_back(p + rng.gaussian(0.0, sigma) * p.normalized());
    }
    const SE2 estimate = minimize(target, source, pairs, ErrorMetric::kPointToPoint, truth);
    sum += nees(estimate, truth, censi_covariance(target, source, estimate, pairs, ErrorMetric::kPointToPoint, {sigma}));
  }
  const double mean = sum / kTrials;
  EXPECT_GT(mean, kNeesLow);
  EXPECT_LT(mean, kNeesHigh);
}

TEST(CensiCovariance, PointToLineMatchesMonteCarloSpreadOnSimulatedScans) {
  testing::ScanPairOptions options;
  options.T_world_target = SE2(-1.0, 0.5, 0.2);
  options.T_target_source = SE2(0.1, 0.05, 0.03);
  options.range_sigma = 0.01;
  double sum = 0.0;
  int used = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    options.seed = 100 + static_cast<std::uint64_t>(trial);
    const testing::ScanPair pair = testing::make_scan_pair(testing::room_world(), options);
    // Segments between scan neighbours along the same wall, found at the true pose.
    const KdTree2 tree(pair.target.points);
    std::vector<Correspondence> pairs;
    for (std::size_t i = 0; i < pair.source.size(); ++i) {
      const Point2 q = pair.T_target_source * pair.source.points[i];
      const std::vector<Neighbor> near = tree.nearest_k(q, 2);
      if (near.size() < 2 || near[1].squared_distance > 0.2 * 0.2) continue;
      const std::size_t a = std::min(near[0].index, near[1].index);
      const std::size_t b = std::max(near[0].index, near[1].index);
      if (b != a + 1) continue;
      pairs.push_back({.source = i, .target = a, .target2 = b});
    }
    const SE2 estimate = minimize(pair.target, pair.source, pairs, ErrorMetric::kPointToLine, pair.T_target_source);
    const Covariance3 covariance =
        censi_covariance(pair.target, pair.source, estimate, pairs, ErrorMetric::kPointToLine, {options.range_sigma});
    sum += nees(estimate, pair.T_target_source, covariance);
    ++used;
  }
  const double mean = sum / used;
  EXPECT_GT(mean, kNeesLow);
  EXPECT_LT(mean, kNeesHigh);
}

TEST(CensiCovariance, UndefinedWithTooFewPairs) {
  PointCloud2 cloud;
  cloud.points = {{1.0, 0.0}, {0.0, 1.0}};
  const std::vector<Correspondence> pairs{{.source = 0, .target = 0}, {.source = 1, .target = 1}};
  EXPECT_GE(censi_covariance(cloud, cloud, SE2(), pairs, ErrorMetric::kPointToPoint).diagonal().minCoeff(), 1e5);
  EXPECT_GE(hessian_covariance(cloud, cloud, SE2(), pairs, ErrorMetric::kPointToPoint).diagonal().minCoeff(), 1e5);
}

TEST(HessianCovariance, ScalesWithTheResidualVariance) {
  Rng rng(5);
  PointCloud2 target;
  PointCloud2 source;
  std::vector<Correspondence> pairs;
  for (std::size_t i = 0; i < 200; ++i) {
    const Point2 q(rng.uniform(-5.0, 5.0), rng.uniform(-5.0, 5.0));
    target.points.push_back(q);
    source.points.push_back(q + Point2(rng.gaussian(0.0, 0.05), rng.gaussian(0.0, 0.05)));
    pairs.push_back({.source = i, .target = i});
  }
  const Covariance3 covariance = hessian_covariance(target, source, SE2(), pairs, ErrorMetric::kPointToPoint);
  // Translation variance ~ sigma^2 / n = 0.0025 / 200.
  EXPECT_NEAR(covariance(0, 0), 0.0025 / 200.0, 0.3 * 0.0025 / 200.0);
  EXPECT_NEAR(rms_residual(target, source, SE2(), pairs, ErrorMetric::kPointToPoint), 0.05 * std::sqrt(2.0), 0.01);
}

}  // namespace
}  // namespace slam2d
