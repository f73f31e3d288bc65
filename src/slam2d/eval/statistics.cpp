// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/eval/statistics.hpp"

#include <algorithm>
#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

ErrorStatistics compute_statistics(std::span<const double> values) {
  ErrorStatistics statistics;
  if (values.empty()) return statistics;
  const double n = static_cast<double>(values.size());
  double sum = 0.0;
  for (const double v : values) sum += v;
  statistics.mean = sum / n;
  double squared_deviations = 0.0;
  for (const double v : values) squared_deviations += (v - statistics.mean) * (v - statistics.mean);
  statistics.std = std::sqrt(squared_deviations / n);
  statistics.max = *std::max_element(values.begin(), values.end());
  return statistics;
}

double root_mean_square(std::span<const double> values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (const double v : values) sum += v * v;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle), values.end());
  const double upper = values[middle];
  if (values.size() % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle));
  return 0.5 * (lower + upper);
}

double percentile(std::vector<double> values, double p) {
  check(p >= 0.0 && p <= 100.0, "percentile: p must be in [0, 100]");
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = p / 100.0 * static_cast<double>(values.size() - 1);
  const auto lower = static_cast<std::size_t>(std::floor(rank));
  const std::size_t upper = std::min(lower + 1, values.size() - 1);
  return values[lower] + (rank - static_cast<double>(lower)) * (values[upper] - values[lower]);
}

std::vector<double> squared(std::span<const double> values) {
  std::vector<double> result;
  result.reserve(values.size());
  for (const double v : values) result.push_back(v * v);
  return result;
}

}  // namespace slam2d
