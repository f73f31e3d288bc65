// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/resampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "slam2d/core/error.hpp"

namespace slam2d {

std::vector<double> normalized_weights(const std::vector<double>& log_weights) {
  check(!log_weights.empty(), "normalized_weights: no particles");
  double max_log = -std::numeric_limits<double>::infinity();
  for (const double l : log_weights) {
    check(!std::isnan(l) && l != std::numeric_limits<double>::infinity(), "normalized_weights: NaN or +inf log weight");
    max_log = std::max(max_log, l);
  }
  std::vector<double> weights(log_weights.size(), 1.0 / static_cast<double>(log_weights.size()));
  if (max_log == -std::numeric_limits<double>::infinity()) return weights;
  double sum = 0.0;
  for (std::size_t i = 0; i < log_weights.size(); ++i) {
    weights[i] = std::exp(log_weights[i] - max_log);
    sum += weights[i];
  }
  for (double& w : weights) w /= sum;
  return weights;
}

double effective_sample_size(const std::vector<double>& weights) {
  check(!weights.empty(), "effective_sample_size: no particles");
  double sum_squares = 0.0;
  for (const double w : weights) sum_squares += w * w;
  return 1.0 / sum_squares;  // Eq. (20)
}

std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, double r, std::size_t count) {
  check(!weights.empty() && count > 0, "low_variance_resample: no particles");
  const std::size_t n = weights.size();
  const double step = 1.0 / static_cast<double>(count);
  check(r >= 0.0 && r < step, "low_variance_resample: r must lie in [0, 1 / M)");
  std::vector<std::size_t> indices;
  indices.reserve(count);
  double c = weights[0];  // Table 4.4, lines 3-4
  std::size_t i = 0;
  for (std::size_t m = 0; m < count; ++m) {
    const double u = r + static_cast<double>(m) * step;  // line 6
    while (u > c && i + 1 < n) c += weights[++i];         // lines 7-10 (i + 1 < n guards rounding)
    indices.push_back(i);                                 // line 11
  }
  return indices;
}

std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, double r) {
  return low_variance_resample(weights, r, weights.size());
}

std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, Rng& rng, std::size_t count) {
  check(!weights.empty() && count > 0, "low_variance_resample: no particles");
  const double step = 1.0 / static_cast<double>(count);
  return low_variance_resample(weights, std::min(rng.uniform() * step, std::nextafter(step, 0.0)), count);
}

std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, Rng& rng) {
  return low_variance_resample(weights, rng, weights.size());
}

}  // namespace slam2d
