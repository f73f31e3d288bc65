// SPDX-License-Identifier: BSD-3-Clause
// Angles, LaserScan conversion, covariance helpers, trajectories, RNG and errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/jackknife.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/core/trajectory.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::poses_near;

TEST(Angles, NormalizeWrapsToHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(normalize_angle(0.25), 0.25);
  EXPECT_NEAR(normalize_angle(std::numbers::pi), -std::numbers::pi, 1e-15);
  EXPECT_NEAR(normalize_angle(-std::numbers::pi), -std::numbers::pi, 1e-15);
  EXPECT_NEAR(normalize_angle(5 * std::numbers::pi + 0.1), -std::numbers::pi + 0.1, 1e-12);
  EXPECT_NEAR(angle_difference(-3.1, 3.1), 2 * std::numbers::pi - 6.2, 1e-12);
  EXPECT_NEAR(rad_to_deg(deg_to_rad(37.5)), 37.5, 1e-12);
}

LaserScan four_beam_scan() {
  LaserScan scan;
  scan.angle_min = -std::numbers::pi / 2;
  scan.angle_increment = std::numbers::pi / 2;
  scan.range_min = 0.1;
  scan.range_max = 10.0;
  scan.ranges = {1.0, std::numeric_limits<double>::quiet_NaN(), 10.0, 0.05};
  return scan;
}

TEST(LaserScan, ConversionDropsInvalidBeamsAndCountsThem) {
  LaserScan scan = four_beam_scan();
  scan.ranges.push_back(std::numeric_limits<double>::infinity());
  scan.ranges.push_back(2.0);  // beam 5: -pi/2 + 5 pi/2 = 2 pi, straight ahead
  const ScanPoints result = to_point_cloud(scan, ScanFrame::kSensor);
  EXPECT_EQ(result.dropped_nonfinite, 2u);
  EXPECT_EQ(result.dropped_out_of_range, 2u);
  ASSERT_EQ(result.cloud.size(), 2u);
  EXPECT_EQ(result.beam_indices, (std::vector<std::size_t>{0, 5}));
  EXPECT_NEAR(result.cloud.points[0].x(), 0.0, 1e-12);
  EXPECT_NEAR(result.cloud.points[0].y(), -1.0, 1e-12);
  EXPECT_NEAR(result.cloud.points[1].x(), 2.0, 1e-12);
  EXPECT_NEAR(result.cloud.points[1].y(), 0.0, 1e-12);
}

TEST(LaserScan, RobotFrameAppliesTheMountingPose) {
  LaserScan scan = four_beam_scan();
  scan.T_robot_sensor = SE2(0.5, 0.0, std::numbers::pi);  // rear-facing, 0.5 m ahead
  const ScanPoints result = to_point_cloud(scan, ScanFrame::kRobot);
  ASSERT_EQ(result.cloud.size(), 1u);
  EXPECT_NEAR(result.cloud.points[0].x(), 0.5, 1e-12);
  EXPECT_NEAR(result.cloud.points[0].y(), 1.0, 1e-12);
  EXPECT_NEAR(scan.angle_max(), std::numbers::pi, 1e-12);
}

TEST(Covariance, ComposeMatchesMonteCarlo) {
  const SE2 a(1.0, 2.0, 0.5), b(3.0, -1.0, -0.2);
  const Covariance3 cov_a = covariance_from_sigmas(0.05, 0.02, 0.01);
  const Covariance3 cov_b = covariance_from_sigmas(0.03, 0.04, 0.02);
  const Covariance3 predicted = compose_covariance(a, cov_a, b, cov_b);
  Rng rng(3);
  const int n = 200000;
  std::vector<Eigen::Vector3d> samples;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  const SE2 ab = a * b;
  for (int i = 0; i < n; ++i) {
    const SE2 sa(a.x() + rng.gaussian(0, 0.05), a.y() + rng.gaussian(0, 0.02), a.theta() + rng.gaussian(0, 0.01));
    const SE2 sb(b.x() + rng.gaussian(0, 0.03), b.y() + rng.gaussian(0, 0.04), b.theta() + rng.gaussian(0, 0.02));
    const SE2 s = sa * sb;
    samples.emplace_back(s.x() - ab.x(), s.y() - ab.y(), angle_difference(s.theta(), ab.theta()));
    mean += samples.back();
  }
  mean /= n;
  Covariance3 empirical = Covariance3::Zero();
  for (const auto& s : samples) empirical += (s - mean) * (s - mean).transpose();
  empirical /= n - 1;
  EXPECT_LT((empirical - predicted).cwiseAbs().maxCoeff(), 0.03 * predicted.cwiseAbs().maxCoeff());
}

TEST(Covariance, ValidityPositiveDefinitenessAndEllipse) {
  Covariance3 cov = covariance_from_sigmas(2.0, 1.0, 0.1);
  EXPECT_TRUE(is_valid_covariance(cov));
  const Ellipse e = translation_ellipse(rotate_covariance(cov, 0.3));
  EXPECT_NEAR(e.major, 2.0, 1e-12);
  EXPECT_NEAR(e.minor, 1.0, 1e-12);
  EXPECT_NEAR(std::abs(std::sin(e.angle - 0.3)), 0.0, 1e-9);
  Covariance3 bad = cov;
  bad(0, 0) = -1.0;
  EXPECT_FALSE(is_valid_covariance(bad));
  EXPECT_TRUE(is_valid_covariance(make_positive_definite(bad)));
  bad(0, 1) = 0.5;
  EXPECT_FALSE(is_valid_covariance(bad));
  EXPECT_TRUE(information_from_covariance(cov).isApprox(Eigen::Vector3d(0.25, 1.0, 100.0).asDiagonal().toDenseMatrix()));
  EXPECT_THROW(information_from_covariance(Covariance3::Zero()), Error);
}

// Wilson-Hilferty against the exact quantiles (tables; scipy.stats.chi2.ppf): within 2 % from 3
// degrees of freedom on, 0.2 % from 30, for the gates the code uses.
TEST(Covariance, ChiSquareQuantileMatchesTheTables) {
  EXPECT_NEAR(chi_square_quantile(3.0, 3.0902), 16.266, 0.02 * 16.266);   // 99.9 %
  EXPECT_NEAR(chi_square_quantile(3.0, 1.6449), 7.815, 0.01 * 7.815);     // 95 %
  EXPECT_NEAR(chi_square_quantile(30.0, 3.0902), 59.703, 0.002 * 59.703);
  EXPECT_NEAR(chi_square_quantile(300.0, 3.0902), 381.43, 0.002 * 381.43);
  EXPECT_NEAR(chi_square_quantile(99.0, 2.326), 134.64, 0.01 * 134.64);   // 99 %, KLD-sampling's
  EXPECT_NEAR(chi_square_quantile(3.0, 0.0), 2.366, 0.01 * 2.366);        // the median
  EXPECT_LT(chi_square_quantile(30.0, 3.0902), chi_square_quantile(31.0, 3.0902));
  EXPECT_GE(chi_square_quantile(1.0, -10.0), 0.0);                        // never negative
}

TEST(Trajectory, InterpolatesBetweenStamps) {
  Trajectory trajectory;
  trajectory.push_back(0.0, SE2(0, 0, 0));
  trajectory.push_back(1.0, SE2(2, 0, 1.0));
  trajectory.push_back(3.0, SE2(2, 4, 1.0));
  EXPECT_TRUE(poses_near(*trajectory.interpolate(0.5), SE2(1, 0, 0.5), 1e-12, 1e-12));
  EXPECT_TRUE(poses_near(*trajectory.interpolate(2.0), SE2(2, 2, 1.0), 1e-12, 1e-12));
  EXPECT_TRUE(poses_near(*trajectory.interpolate(3.0), SE2(2, 4, 1.0), 1e-12, 1e-12));
  EXPECT_FALSE(trajectory.interpolate(-0.1).has_value());
  EXPECT_FALSE(trajectory.interpolate(3.1).has_value());
  EXPECT_NEAR(trajectory.path_length(), 6.0, 1e-12);
}

TEST(Trajectory, BackwardStampsAreCountedAndSortable) {
  Trajectory trajectory;
  for (double t : {0.0, 1.0, 0.5, 2.0, 1.5}) trajectory.push_back(t, SE2(t, 0, 0));
  EXPECT_EQ(trajectory.backwards_steps(), 2u);
  EXPECT_THROW(trajectory.interpolate(1.2), Error);
  const Trajectory sorted = trajectory.sorted_by_stamp();
  EXPECT_TRUE(sorted.is_monotonic());
  EXPECT_TRUE(poses_near(*sorted.interpolate(1.25), SE2(1.25, 0, 0), 1e-12, 1e-12));

  const StampIndex index(trajectory);
  EXPECT_EQ(index.nearest(0.5004, 0.001), std::optional<std::size_t>(2));
  EXPECT_EQ(index.nearest(1.4995, 0.001), std::optional<std::size_t>(4));
  EXPECT_FALSE(index.nearest(1.25, 0.001).has_value());
  EXPECT_FALSE(index.nearest(-1.0, 0.5).has_value());
  EXPECT_EQ(index.nearest(10.0, 8.5), std::optional<std::size_t>(3));
}

TEST(Rng, SameSeedSameSequenceAndPortableValues) {
  Rng a(42), b(42), c(43);
  for (int i = 0; i < 100; ++i) {
    const double x = a.gaussian();
    EXPECT_EQ(x, b.gaussian());
    EXPECT_NE(x, c.gaussian());
  }
  // mt19937_64's 10000th output from the default seed is fixed by the C++ standard.
  Rng standard(5489u);
  std::uint64_t value = 0;
  for (int i = 0; i < 10000; ++i) value = standard.next_u64();
  EXPECT_EQ(value, 9981545732273789042ull);
}

TEST(Rng, DistributionsHaveTheRightMoments) {
  Rng rng(1);
  const int n = 200000;
  double sum = 0, sum_sq = 0, uniform_sum = 0;
  std::set<std::size_t> indices;
  for (int i = 0; i < n; ++i) {
    const double g = rng.gaussian(1.0, 2.0);
    sum += g;
    sum_sq += g * g;
    const double u = rng.uniform(-1.0, 3.0);
    ASSERT_GE(u, -1.0);
    ASSERT_LT(u, 3.0);
    uniform_sum += u;
    indices.insert(rng.uniform_index(7));
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 1.0, 0.02);
  EXPECT_NEAR(std::sqrt(sum_sq / n - mean * mean), 2.0, 0.02);
  EXPECT_NEAR(uniform_sum / n, 1.0, 0.01);
  EXPECT_EQ(indices.size(), 7u);
  EXPECT_EQ(*indices.rbegin(), 6u);
}

TEST(Rng, ZigguratNormalFollowsTheNormalDistribution) {
  Rng rng(7);
  const int n = 400000;
  std::vector<double> samples(n);
  double sum = 0, sum_sq = 0, sum_4 = 0;
  int beyond_tail = 0;
  for (double& x : samples) {
    x = rng.normal();
    sum += x;
    sum_sq += x * x;
    sum_4 += x * x * x * x;
    beyond_tail += std::abs(x) > 3.6541528853610088 ? 1 : 0;  // drawn by the tail algorithm
  }
  EXPECT_NEAR(sum / n, 0.0, 0.006);       // 4 standard errors
  EXPECT_NEAR(sum_sq / n, 1.0, 0.009);    // sd of the sample variance: sqrt(2 / n)
  EXPECT_NEAR(sum_4 / n, 3.0, 0.07);      // sd of the fourth moment: sqrt(96 / n)
  // P(|x| > r) = erfc(r / sqrt 2) = 2.58e-4: 103 expected, Poisson sd 10.
  EXPECT_NEAR(beyond_tail, 103.3, 45.0);
  // Kolmogorov-Smirnov against the normal CDF: 1.95 / sqrt(n) is the 0.1 % critical value.
  std::sort(samples.begin(), samples.end());
  double ks = 0.0;
  for (int i = 0; i < n; ++i) {
    const double cdf = 0.5 * std::erfc(-samples[i] / std::sqrt(2.0));
    ks = std::max({ks, std::abs(cdf - static_cast<double>(i) / n), std::abs(cdf - static_cast<double>(i + 1) / n)});
  }
  EXPECT_LT(ks, 1.95 / std::sqrt(static_cast<double>(n)));
  // Seeded: the same sequence again.
  Rng a(11), b(11);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.normal(), b.normal());
}

TEST(Rng, SplitStreamsAreIndependentAndReproducible) {
  Rng a(9), b(9);
  Rng a1 = a.split(1), b1 = b.split(1);
  Rng a2 = a.split(2);
  const double x = a1.uniform();
  EXPECT_EQ(x, b1.uniform());
  EXPECT_NE(x, a2.uniform());
}

// For the sample mean the jackknife standard error is exactly the textbook s / sqrt(n), with s the
// sample standard deviation (n - 1 in the denominator): e_i = (n mean - x_i) / (n - 1).
TEST(Jackknife, OfTheMeanIsTheStandardErrorOfTheMean) {
  const std::vector<double> x{0.3, -1.2, 2.5, 0.9, 4.1, -0.7, 1.6};
  const auto n = static_cast<double>(x.size());
  double mean = 0.0;
  for (const double v : x) mean += v / n;
  double ss = 0.0;
  for (const double v : x) ss += (v - mean) * (v - mean);
  std::vector<double> leave_one_out;
  for (const double v : x) leave_one_out.push_back((n * mean - v) / (n - 1.0));
  EXPECT_NEAR(slam2d::jackknife_standard_error(leave_one_out), std::sqrt(ss / (n - 1.0) / n), 1e-12);
  EXPECT_EQ(slam2d::jackknife_standard_error(std::vector<double>{1.0}), 0.0);
}

TEST(Errors, ParseErrorNamesFileAndLine) {
  const ParseError error("logs/a.clf", 12, "FLASER: range 3 is NaN");
  EXPECT_STREQ(error.what(), "logs/a.clf:12: FLASER: range 3 is NaN");
  EXPECT_EQ(error.line(), 12u);
  EXPECT_STREQ(ParseError("m.yaml", 0, "no image").what(), "m.yaml: no image");
  EXPECT_THROW(check(false, "bad"), Error);
}

TEST(OccupancyMap, CellsAndCoordinatesAgree) {
  OccupancyMap map;
  map.resolution = 0.5;
  map.origin = SE2(-1.0, 2.0, std::numbers::pi / 2);
  map.width = 4;
  map.height = 3;
  map.cells.assign(12, OccupancyMap::kUnknown);
  map.at(3, 2) = OccupancyMap::kOccupied;
  EXPECT_EQ(map.cells[11], OccupancyMap::kOccupied);
  const Eigen::Vector2d centre = map.cell_center(3, 2);
  EXPECT_NEAR(centre.x(), -1.0 - 1.25, 1e-12);
  EXPECT_NEAR(centre.y(), 2.0 + 1.75, 1e-12);
  EXPECT_EQ(map.cell_of(centre), Eigen::Vector2i(3, 2));
  EXPECT_FALSE(map.contains(4, 0));
}

}  // namespace
}  // namespace slam2d
