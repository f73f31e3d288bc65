// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/detail/order_statistics.hpp"

#include <algorithm>
#include <bit>

namespace slam2d {
namespace {

constexpr int kMantissaBits = 3;
constexpr int kMaxBuckets = 256;
constexpr double kSmallest = 0x1p-30;

std::uint64_t key(double value) { return std::bit_cast<std::uint64_t>(value) >> (52 - kMantissaBits); }

}  // namespace

BucketSelector::BucketSelector(double largest)
    : buckets_(largest > kSmallest
                   ? static_cast<int>(std::min<std::uint64_t>(key(largest) - key(kSmallest), kMaxBuckets - 1)) + 1
                   : 1) {}

std::pair<double, double> BucketSelector::ranks(const double* values, std::size_t n, std::size_t a, std::size_t b,
                                                std::vector<std::uint8_t>& keys, std::vector<double>& scratch) const {
  keys.resize(n);
  scratch.resize(n);
  std::uint8_t* const key_of = keys.data();
  double* const gathered = scratch.data();
  std::uint32_t counts[kMaxBuckets] = {};
  const std::int64_t lowest_key = static_cast<std::int64_t>(key(kSmallest));
  const std::int64_t highest = buckets_ - 1;  // (a local: the byte-sized key stores may alias members)
  int top = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int bucket = static_cast<int>(std::clamp<std::int64_t>(static_cast<std::int64_t>(key(values[i])) - lowest_key, 0, highest));
    key_of[i] = static_cast<std::uint8_t>(bucket);
    ++counts[bucket];
    top = std::max(top, bucket);
  }
  // From the top bucket down: `below` counts the values in the buckets under the current one.
  int bucket_a = 0, bucket_b = 0;
  std::size_t below_a = 0, below_b = 0;
  std::size_t above = 0;
  bool found_b = false;
  for (int k = top; k >= 0; --k) {
    const std::size_t below = n - above - counts[k];
    if (!found_b && below <= b) {
      bucket_b = k, below_b = below, found_b = true;
    }
    if (below <= a) {
      bucket_a = k, below_a = below;
      break;
    }
    above += counts[k];
  }
  // Gathered without a branch, in scan order: bucket a's values all lie below bucket b's.
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    gathered[count] = values[i];
    count += (key_of[i] == bucket_a) | (key_of[i] == bucket_b) ? 1 : 0;
  }
  const std::size_t rank_a = a - below_a;
  const std::size_t rank_b = (bucket_b == bucket_a ? 0 : counts[bucket_a]) + b - below_b;
  std::nth_element(gathered, gathered + rank_a, gathered + count);
  const double value_a = gathered[rank_a];
  if (rank_b > rank_a) std::nth_element(gathered + rank_a + 1, gathered + rank_b, gathered + count);
  return {value_a, gathered[rank_b]};
}

}  // namespace slam2d
