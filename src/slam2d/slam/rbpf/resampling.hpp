#pragma once
// Selective resampling for particle filters: G. Grisetti, C. Stachniss, W. Burgard, "Improved
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

/// Thrun Table 4.4: the particle index drawn for each of the N pointers r + m / N, m = 0..N-1,
/// over the cumulative normalised weights; r in [0, 1 / N). Returns N indices, non-decreasing.
/// Throws Error for an empty vector or r outside [0, 1 / N).
std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, double r);

/// The same with r drawn uniformly in [0, 1 / N) from `rng`.
std::vector<std::size_t> low_variance_resample(const std::vector<double>& weights, Rng& rng);

}  // namespace slam2d
