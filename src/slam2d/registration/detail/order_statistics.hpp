// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Exact order statistics of non-negative values by their bit patterns, for the trimming of
// PL-ICP (Eq. (3) of Censi 2008 takes two quantiles of the pair distances at every iteration).
//
// For doubles >= 0 the IEEE pattern, read as an integer, grows with the value, so its top bits
// (the exponent and the first kMantissaBits of the mantissa) sort the values into buckets an
// eighth of an octave wide. One pass counts the buckets, a walk down the counts finds the
// buckets that hold the two ranks, a second pass gathers those buckets' few values, and
// std::nth_element finishes among them. Exact, and about half the work of a quickselect over
// the whole array, whose partitions have no order to use.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace slam2d {

class BucketSelector {
 public:
  /// Values in [2^-30, largest] get buckets of their own; smaller ones share the lowest bucket,
  /// larger ones the highest (still exact, only slower if many fall there).
  explicit BucketSelector(double largest);

  /// The values at ranks a <= b < n (0-based, as if sorted ascending) of values[0, n), n > 0,
  /// every value >= 0 (not NaN). `keys` and `scratch` are buffers, resized as needed.
  std::pair<double, double> ranks(const double* values, std::size_t n, std::size_t a, std::size_t b,
                                  std::vector<std::uint8_t>& keys, std::vector<double>& scratch) const;

 private:
  int buckets_;
};

}  // namespace slam2d
