// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Summary statistics of error samples, shared by the evaluation metrics (relation error of
// Kuemmerle et al. 2009, ATE and RPE of Sturm et al. 2012).

#include <span>
#include <vector>

namespace slam2d {

/// Mean, standard deviation and maximum of a set of errors. `std` is the POPULATION standard
/// deviation (sum of squared deviations divided by N, not N - 1), as in Kuemmerle et al. 2009's
/// tables. All three are zero for an empty set.
struct ErrorStatistics {
  double mean = 0.0;
  double std = 0.0;
  double max = 0.0;
};

/// Mean, population standard deviation (two-pass) and maximum of `values`; zeros when empty.
ErrorStatistics compute_statistics(std::span<const double> values);

/// sqrt(mean(v^2)); zero when empty.
double root_mean_square(std::span<const double> values);

/// The median (mean of the two middle values for an even count); zero when empty.
double median(std::vector<double> values);

/// The p-th percentile, p in [0, 100], interpolating linearly between the order statistics
/// (numpy's default: rank p / 100 * (n - 1)); zero when empty. Throws Error for p outside [0, 100].
double percentile(std::vector<double> values, double p);

/// The squares of `values`, element by element.
std::vector<double> squared(std::span<const double> values);

}  // namespace slam2d
