// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The jackknife standard error (Quenouille 1956; Tukey 1958; Efron & Stein 1981): an estimate's
// spread from its re-estimates with each of g groups of the data left out in turn.

#include <cmath>
#include <span>

namespace slam2d {

/// sqrt((g - 1) / g * sum_i (e_i - mean(e))^2) over the g leave-one-group-out estimates e_i; zero
/// for fewer than two.
inline double jackknife_standard_error(std::span<const double> leave_one_out) {
  const auto g = static_cast<double>(leave_one_out.size());
  if (leave_one_out.size() < 2) return 0.0;
  double mean = 0.0;
  for (const double e : leave_one_out) mean += e / g;
  double spread = 0.0;
  for (const double e : leave_one_out) spread += (e - mean) * (e - mean);
  return std::sqrt((g - 1.0) / g * spread);
}

}  // namespace slam2d
