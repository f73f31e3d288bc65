#include "slam2d/core/rng.hpp"

#include <cmath>

#include "slam2d/core/error.hpp"

namespace slam2d {

std::uint64_t mix_seed(std::uint64_t value) {
  value += 0x9E3779B97F4A7C15ull;
  value = (value ^ (value >> 30)) * 0xBF58476D1CE4E5B9ull;
  value = (value ^ (value >> 27)) * 0x94D049BB133111EBull;
  return value ^ (value >> 31);
}

std::size_t Rng::uniform_index(std::size_t n) {
  check(n > 0, "Rng::uniform_index: empty range");
  const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
  std::uint64_t value;
  do {
    value = engine_();
  } while (value >= limit);
  return static_cast<std::size_t>(value % n);
}

double Rng::gaussian(double mean, double sigma) {
  if (has_spare_) {
    has_spare_ = false;
    return mean + sigma * spare_;
  }
  double u, v, s;
  do {
    u = uniform(-1.0, 1.0);
    v = uniform(-1.0, 1.0);
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  const double factor = std::sqrt(-2.0 * std::log(s) / s);
  spare_ = v * factor;
  has_spare_ = true;
  return mean + sigma * u * factor;
}

Rng Rng::split(std::uint64_t stream) { return Rng(mix_seed(engine_() ^ mix_seed(stream))); }

}  // namespace slam2d
