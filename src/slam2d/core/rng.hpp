// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Seeded random numbers that give the same sequence on every platform and standard library:
// std::mt19937_64's output is fixed by the standard, the distributions here are our own.

#include <cstddef>
#include <cstdint>
#include <random>

namespace slam2d {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  std::uint64_t next_u64() { return engine_(); }
  /// Uniform in [0, 1), 53 bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Uniform in [low, high).
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  /// Uniform integer in [0, n), n > 0, without modulo bias.
  std::size_t uniform_index(std::size_t n);
  /// Normal with the given mean and standard deviation (Marsaglia's polar method).
  double gaussian(double mean = 0.0, double sigma = 1.0);
  /// Standard normal by the ziggurat method (G. Marsaglia, W. W. Tsang, "The ziggurat method for
  /// generating random variables", J. Stat. Software 5(8), 2000; 256 layers): one 64-bit draw
  /// and a multiply for 99 % of the samples, several times cheaper than gaussian(), for the inner
  /// loops that draw millions (particle motion). Exact in distribution; another sequence than
  /// gaussian().
  double normal();
  /// True with probability p.
  bool bernoulli(double p) { return uniform() < p; }
  /// An independent generator, e.g. one per particle or thread, derived from this one's seed.
  Rng split(std::uint64_t stream);

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

/// SplitMix64: mixes a 64-bit value into a well-spread seed.
std::uint64_t mix_seed(std::uint64_t value);

}  // namespace slam2d
