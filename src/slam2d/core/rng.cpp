// SPDX-License-Identifier: BSD-3-Clause
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

namespace {

// Marsaglia & Tsang's 256 layers of equal area under f(x) = exp(-x^2 / 2): layer i > 0 is the
// rectangle [0, x[i]] x [f(x[i]), f(x[i + 1])]; layer 0 is the rectangle [0, r] x [0, f(r)] plus
// the tail beyond r, drawn as a rectangle of width x[0] = v / f(r).
struct ZigguratTables {
  static constexpr int kLayers = 256;
  static constexpr double kR = 3.6541528853610088;      // x[1], the start of the tail
  static constexpr double kArea = 4.92867323399e-3;      // v, the area of every layer
  double x[kLayers + 1];
  double f[kLayers + 1];
  ZigguratTables() {
    const auto density = [](double t) { return std::exp(-0.5 * t * t); };
    x[0] = kArea / density(kR);
    x[1] = kR;
    for (int i = 1; i < kLayers - 1; ++i) x[i + 1] = std::sqrt(-2.0 * std::log(kArea / x[i] + density(x[i])));
    x[kLayers - 1 + 1] = 0.0;
    for (int i = 0; i <= kLayers; ++i) f[i] = density(x[i]);
  }
};

}  // namespace

double Rng::normal() {
  static const ZigguratTables tables;
  for (;;) {
    const std::uint64_t bits = engine_();
    const int layer = static_cast<int>(bits & 0xFF);
    const double sign = (bits & 0x100) != 0 ? -1.0 : 1.0;
    const double x = static_cast<double>(bits >> 11) * 0x1.0p-53 * tables.x[layer];
    if (x < tables.x[layer + 1]) return sign * x;  // inside the layer's core rectangle
    if (layer == 0) {
      // The tail beyond r (Marsaglia 1964): r + a with a ~ Exp(r), accepted with exp(-a^2 / 2).
      double a, b;
      do {
        a = -std::log(1.0 - uniform()) / ZigguratTables::kR;
        b = -std::log(1.0 - uniform());
      } while (2.0 * b < a * a);
      return sign * (ZigguratTables::kR + a);
    }
    // The wedge between the rectangle and the curve.
    const double y = tables.f[layer] + uniform() * (tables.f[layer + 1] - tables.f[layer]);
    if (y < std::exp(-0.5 * x * x)) return sign * x;
  }
}

Rng Rng::split(std::uint64_t stream) { return Rng(mix_seed(engine_() ^ mix_seed(stream))); }

}  // namespace slam2d
