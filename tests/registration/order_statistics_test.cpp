// SPDX-License-Identifier: BSD-3-Clause
// BucketSelector (order_statistics.hpp), the exact two-rank selection behind PL-ICP's trimming,
// against a sorted copy: every pair of ranks of value sets built to stress the buckets (ties,
// zeros, values below and above the bucketed range, all in one bucket).

#include "slam2d/registration/detail/order_statistics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace slam2d {
namespace {

// Every rank pair a <= b of `values` against the sorted values.
void expect_every_rank_pair(const std::vector<double>& values, double largest) {
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  const BucketSelector selector(largest);
  std::vector<std::uint8_t> keys;
  std::vector<double> scratch;
  const std::size_t n = values.size();
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a; b < n; b += 1 + n / 17) {
      const auto [value_a, value_b] = selector.ranks(values.data(), n, a, b, keys, scratch);
      ASSERT_EQ(value_a, sorted[a]) << "n " << n << " a " << a << " b " << b;
      ASSERT_EQ(value_b, sorted[b]) << "n " << n << " a " << a << " b " << b;
    }
  }
}

TEST(BucketSelector, RanksEqualTheSortedValues) {
  std::mt19937 rng(7);
  std::exponential_distribution<double> distance(200.0);  // like point-to-line distances, mean 5 mm
  std::vector<double> values;
  for (int k = 0; k < 180; ++k) values.push_back(distance(rng));
  expect_every_rank_pair(values, 0.5);
}

TEST(BucketSelector, TiesZerosAndValuesOutsideTheRange) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<double> values;
  for (int k = 0; k < 60; ++k) values.push_back(0.0);                  // a scan matched to itself
  for (int k = 0; k < 30; ++k) values.push_back(1e-14 * uniform(rng));  // below 2^-30: the lowest bucket
  for (int k = 0; k < 30; ++k) values.push_back(0.25);                  // ties inside one bucket
  for (int k = 0; k < 30; ++k) values.push_back(0.2500001 + 1e-9 * k);  // the same bucket, distinct
  for (int k = 0; k < 30; ++k) values.push_back(3.0 + uniform(rng));    // above `largest`: the highest bucket
  std::shuffle(values.begin(), values.end(), rng);
  expect_every_rank_pair(values, 0.5);
}

TEST(BucketSelector, OneValueAndOneBucket) {
  expect_every_rank_pair({0.003}, 0.5);
  expect_every_rank_pair({0.3, 0.1, 0.2}, 1e-12);  // a degenerate range: one bucket for everything
}

}  // namespace
}  // namespace slam2d
