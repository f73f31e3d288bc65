// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Resampling for particle filters (the RBPF's selective resampling, MCL's draws): G. Grisetti, C. Stachniss, W. Burgard, "Improved
// techniques for grid mapping with Rao-Blackwellized particle filters", IEEE T-RO 23(1), 2007,
// Sec. IV-B, and the low-variance sampler of S. Thrun, W. Burgard, D. Fox, "Probabilistic
// Robotics", 2005, Table 4.4.

#include <cstddef>
#include <vector>

#include "slam2d/core/rng.hpp"

namespace slam2d {

/// Normalised weights exp(l_i - max l) / sum_j exp(l_j - max l) from log weights (stable for any
/// magnitude). Throws Error for an empty vector or a NaN / +inf log weight; -inf is weight 0
/// unless every log weight is -inf (then all weights are equal).
std::vector<double> normalized_weights(const std::vector<double>& log_weights);

/// N_eff = 1 / sum_i w_i^2 of normalised weights, Grisetti et al. 2007, Eq. (20). In [1, N].
double effective_sample_size(const std::vector<double>& weights);

/// Thrun Table 4.4: the particle index drawn for each of the M pointers r + m / M, m = 0..M-1,
/// over the cumulative normalised weights; r in [0, 1 / M). Returns M indices, non-decreasing.
/// M = `count` (a filter that changes its size, KLD sampling), by default the number of
/// weights. Throws Error for no weights, count 0 or r outside [0, 1 / M).
std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, double r, std::size_t count);
std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, double r);

/// The same with r drawn uniformly in [0, 1 / M) from `rng`.
std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, Rng& rng, std::size_t count);
std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, Rng& rng);

}  // namespace slam2d
