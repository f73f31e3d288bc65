// SPDX-License-Identifier: BSD-3-Clause
// Exact squared Euclidean distance transform (Felzenszwalb and Huttenlocher 2012) against brute force.

#include "slam2d/grid/distance_transform.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"

namespace slam2d {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// min over cells p of |cell - p|^2 + f[p], by trying every p.
std::vector<double> brute_force(int width, int height, const std::vector<double>& f) {
  std::vector<double> out(f.size(), kInf);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double best = kInf;
      for (int py = 0; py < height; ++py) {
        for (int px = 0; px < width; ++px) {
          const double value = f[static_cast<std::size_t>(py) * width + px];
          if (value == kInf) continue;
          best = std::min(best, double((x - px) * (x - px) + (y - py) * (y - py)) + value);
        }
      }
      out[static_cast<std::size_t>(y) * width + x] = best;
    }
  }
  return out;
}

std::vector<std::uint8_t> random_sites(int width, int height, double density, Rng& rng) {
  std::vector<std::uint8_t> sites(static_cast<std::size_t>(width) * height);
  for (auto& site : sites) site = rng.bernoulli(density) ? 1 : 0;
  return sites;
}

std::vector<double> as_function(const std::vector<std::uint8_t>& sites) {
  std::vector<double> f(sites.size());
  for (std::size_t i = 0; i < sites.size(); ++i) f[i] = sites[i] != 0 ? 0.0 : kInf;
  return f;
}

/// Checks distances against brute force and that every nearest site is a site at that distance.
void expect_matches_brute_force(int width, int height, const std::vector<std::uint8_t>& sites) {
  const SquaredDistanceField field = squared_distance_transform_of_sites(width, height, sites, true);
  const std::vector<double> expected = brute_force(width, height, as_function(sites));
  ASSERT_EQ(field.width, width);
  ASSERT_EQ(field.height, height);
  ASSERT_EQ(field.squared_distances.size(), expected.size());
  ASSERT_EQ(field.nearest_sites.size(), expected.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * width + x;
      ASSERT_EQ(field.squared_distances[i], expected[i]) << "cell " << x << ", " << y;  // exact: integers
      const int site = field.nearest_site(x, y);
      if (expected[i] == kInf) {
        EXPECT_EQ(site, -1);
        continue;
      }
      ASSERT_GE(site, 0);
      ASSERT_NE(sites[static_cast<std::size_t>(site)], 0);
      const int sx = site % width;
      const int sy = site / width;
      EXPECT_EQ((x - sx) * (x - sx) + (y - sy) * (y - sy), expected[i]);
    }
  }
}

TEST(DistanceTransform, OneDimensionalHandComputed) {
  // Sites at 1 and 5, and a raised sample at 3 (offset 1): d = min((q-1)^2, (q-5)^2, (q-3)^2 + 1).
  const std::vector<double> f{kInf, 0.0, kInf, 1.0, kInf, 0.0, kInf};
  std::vector<double> d(f.size());
  std::vector<int> arg(f.size());
  distance_transform_1d(f, d, arg);
  EXPECT_EQ(d, (std::vector<double>{1, 0, 1, 1, 1, 0, 1}));
  EXPECT_EQ(arg[0], 1);
  EXPECT_EQ(arg[3], 3);
  EXPECT_EQ(arg[6], 5);
  EXPECT_EQ(arg[2], 1);  // (2 - 1)^2 + 0 = 1 beats (2 - 3)^2 + 1 = 2
  EXPECT_EQ(arg[4], 5);  // (4 - 5)^2 + 0 = 1 beats (4 - 3)^2 + 1 = 2
}

TEST(DistanceTransform, OneDimensionalRandomFunctionsMatchBruteForce) {
  Rng rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + static_cast<int>(rng.uniform_index(40));
    std::vector<double> f(static_cast<std::size_t>(n));
    for (double& value : f) value = rng.bernoulli(0.3) ? kInf : rng.uniform(0.0, 50.0);
    std::vector<double> d(f.size());
    std::vector<int> arg(f.size());
    distance_transform_1d(f, d, arg);
    const std::vector<double> expected = brute_force(n, 1, f);
    for (int q = 0; q < n; ++q) {
      const auto i = static_cast<std::size_t>(q);
      if (expected[i] == kInf) {
        EXPECT_EQ(d[i], kInf);
        EXPECT_EQ(arg[i], -1);
        continue;
      }
      EXPECT_NEAR(d[i], expected[i], 1e-9 * (1.0 + expected[i]));
      const double offset = q - arg[i];
      EXPECT_NEAR(offset * offset + f[static_cast<std::size_t>(arg[i])], expected[i], 1e-9 * (1.0 + expected[i]));
    }
  }
}

TEST(DistanceTransform, RandomGridsMatchBruteForce) {
  Rng rng(11);
  for (int trial = 0; trial < 60; ++trial) {
    const int width = 1 + static_cast<int>(rng.uniform_index(24));
    const int height = 1 + static_cast<int>(rng.uniform_index(24));
    const double density = trial % 3 == 0 ? 0.01 : trial % 3 == 1 ? 0.1 : 0.5;
    expect_matches_brute_force(width, height, random_sites(width, height, density, rng));
  }
}

TEST(DistanceTransform, RandomSampledFunctionsMatchBruteForce) {
  Rng rng(5);
  for (int trial = 0; trial < 30; ++trial) {
    const int width = 1 + static_cast<int>(rng.uniform_index(16));
    const int height = 1 + static_cast<int>(rng.uniform_index(16));
    std::vector<double> f(static_cast<std::size_t>(width) * height);
    for (double& value : f) value = rng.bernoulli(0.7) ? kInf : rng.uniform(0.0, 30.0);
    const SquaredDistanceField field = squared_distance_transform(width, height, f, true);
    const std::vector<double> expected = brute_force(width, height, f);
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (expected[i] == kInf) {
        EXPECT_EQ(field.squared_distances[i], kInf);
        continue;
      }
      EXPECT_NEAR(field.squared_distances[i], expected[i], 1e-9 * (1.0 + expected[i]));
      const int site = field.nearest_sites[i];
      const int dx = site % width - static_cast<int>(i) % width;
      const int dy = site / width - static_cast<int>(i) / width;
      EXPECT_NEAR(dx * dx + dy * dy + f[static_cast<std::size_t>(site)], expected[i], 1e-9 * (1.0 + expected[i]));
    }
  }
}

TEST(DistanceTransform, SingleRowsAndColumns) {
  Rng rng(3);
  for (int n : {1, 2, 3, 17, 64}) {
    expect_matches_brute_force(n, 1, random_sites(n, 1, 0.2, rng));
    expect_matches_brute_force(1, n, random_sites(1, n, 0.2, rng));
  }
}

TEST(DistanceTransform, EmptyGridIsInfiniteEverywhere) {
  const std::vector<std::uint8_t> sites(12 * 7, 0);
  const SquaredDistanceField field = squared_distance_transform_of_sites(12, 7, sites, true);
  for (double d : field.squared_distances) EXPECT_EQ(d, kInf);
  for (int site : field.nearest_sites) EXPECT_EQ(site, -1);
  const SquaredDistanceField none = squared_distance_transform_of_sites(0, 0, {});
  EXPECT_TRUE(none.squared_distances.empty());
}

TEST(DistanceTransform, AllSitesIsZeroEverywhere) {
  const std::vector<std::uint8_t> sites(9 * 5, 1);
  const SquaredDistanceField field = squared_distance_transform_of_sites(9, 5, sites, true);
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 9; ++x) {
      EXPECT_EQ(field.at(x, y), 0.0);
      EXPECT_EQ(field.nearest_site(x, y), y * 9 + x);
    }
  }
}

TEST(DistanceTransform, SingleSiteGivesExactSquaredDistances) {
  std::vector<std::uint8_t> sites(300 * 200, 0);
  sites[static_cast<std::size_t>(150) * 300 + 40] = 1;  // cell (40, 150)
  const SquaredDistanceField field = squared_distance_transform_of_sites(300, 200, sites);
  EXPECT_TRUE(field.nearest_sites.empty());
  EXPECT_EQ(field.at(40, 150), 0.0);
  EXPECT_EQ(field.at(299, 0), 259.0 * 259.0 + 150.0 * 150.0);
  EXPECT_EQ(field.at(0, 199), 40.0 * 40.0 + 49.0 * 49.0);
}

TEST(DistanceTransform, RejectsBadInput) {
  std::vector<double> f(6, 0.0);
  EXPECT_THROW(squared_distance_transform(2, 2, f), Error);   // wrong sample count
  EXPECT_THROW(squared_distance_transform(-1, -6, f), Error);  // negative size
  f[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(squared_distance_transform(3, 2, f), Error);
  f[2] = -kInf;
  EXPECT_THROW(squared_distance_transform(3, 2, f), Error);
  std::vector<double> out(5);
  EXPECT_THROW(distance_transform_1d(std::vector<double>(6, 0.0), out), Error);
  EXPECT_THROW(squared_distance_transform_of_sites(1 << 15, 1 << 14, std::vector<std::uint8_t>(4)), Error);  // 2^29 cells
}

}  // namespace
}  // namespace slam2d
