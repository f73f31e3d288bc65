// SPDX-License-Identifier: BSD-3-Clause
// Tests of the error statistics shared by the evaluation metrics.

#include "slam2d/eval/statistics.hpp"
#include "slam2d/core/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace slam2d {
namespace {

TEST(Statistics, PopulationStandardDeviationDividesByN) {
  const std::vector<double> values{2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0};
  const ErrorStatistics s = compute_statistics(values);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_DOUBLE_EQ(s.std, 2.0);  // the sample (N - 1) std would be 2.138...
  EXPECT_DOUBLE_EQ(s.max, 9.0);
}

TEST(Statistics, EmptyGivesZeros) {
  const ErrorStatistics s = compute_statistics(std::vector<double>{});
  EXPECT_EQ(s.mean, 0.0);
  EXPECT_EQ(s.std, 0.0);
  EXPECT_EQ(s.max, 0.0);
  EXPECT_EQ(root_mean_square(std::vector<double>{}), 0.0);
  EXPECT_EQ(median({}), 0.0);
}

TEST(Statistics, RootMeanSquareAndMedian) {
  EXPECT_DOUBLE_EQ(root_mean_square(std::vector<double>{3.0, 4.0}), std::sqrt(12.5));
  EXPECT_DOUBLE_EQ(median({5.0, 1.0, 3.0}), 3.0);
  EXPECT_DOUBLE_EQ(median({4.0, 1.0, 3.0, 10.0}), 3.5);
  EXPECT_DOUBLE_EQ(median({7.0}), 7.0);
}

TEST(Statistics, SquaredIsElementwise) {
  const std::vector<double> s = squared(std::vector<double>{-2.0, 0.5});
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0], 4.0);
  EXPECT_EQ(s[1], 0.25);
}

TEST(Statistics, PercentileInterpolatesBetweenOrderStatistics) {
  const std::vector<double> values{4.0, 1.0, 3.0, 2.0, 5.0};  // sorted: 1 2 3 4 5
  EXPECT_DOUBLE_EQ(percentile(values, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(percentile(values, 50.0), 3.0);
  EXPECT_DOUBLE_EQ(percentile(values, 75.0), 4.0);
  EXPECT_DOUBLE_EQ(percentile(values, 95.0), 4.8);  // rank 3.8
  EXPECT_DOUBLE_EQ(percentile(values, 100.0), 5.0);
  EXPECT_DOUBLE_EQ(percentile({}, 50.0), 0.0);
  EXPECT_THROW(percentile(values, 101.0), Error);
}

}  // namespace
}  // namespace slam2d
