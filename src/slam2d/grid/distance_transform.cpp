// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/distance_transform.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// Buffers of Algorithm DT(f), kept across the lines of a 2D transform.
struct Envelope {
  std::vector<int> roots;          // v: the samples whose parabolas form the lower envelope
  std::vector<double> boundaries;  // z: parabola roots[k] is lowest on [boundaries[k], boundaries[k + 1]]

  explicit Envelope(std::size_t n) : roots(n), boundaries(n + 1) {}
};

/// Abscissa where the parabolas rooted at q and p (p < q) intersect (the formula under Algorithm DT(f)).
double intersection(const double* f, int q, int p) {
  const double dq = static_cast<double>(q);
  const double dp = static_cast<double>(p);
  return ((f[q] + dq * dq) - (f[p] + dp * dp)) / (2.0 * dq - 2.0 * dp);
}

/// Algorithm DT(f) over n samples: out[q] = min_p ((q - p)^2 + f[p]); argmin (may be null) gets a
/// minimising p. Infinite samples carry no parabola. f must hold no NaN and no -infinity.
void lower_envelope_transform(const double* f, int n, double* out, int* argmin, Envelope& envelope) {
  int* v = envelope.roots.data();
  double* z = envelope.boundaries.data();
  int k = -1;                    // index of the rightmost parabola of the envelope so far
  for (int q = 0; q < n; ++q) {  // compute the lower envelope
    if (f[q] == kInfinity) continue;
    double s = -kInfinity;
    while (k >= 0) {
      s = intersection(f, q, v[k]);
      if (s > z[k]) break;
      --k;  // parabola v[k] is hidden below the new one
    }
    if (k < 0) s = -kInfinity;
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kInfinity;
  }
  if (k < 0) {  // no finite sample
    for (int q = 0; q < n; ++q) {
      out[q] = kInfinity;
      if (argmin != nullptr) argmin[q] = -1;
    }
    return;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {  // fill in the values of the envelope
    while (z[k + 1] < q) ++k;
    const double offset = static_cast<double>(q - v[k]);
    out[q] = offset * offset + f[v[k]];
    if (argmin != nullptr) argmin[q] = v[k];
  }
}

void check_samples(std::span<const double> f, const char* function) {
  for (const double value : f) {
    if (std::isnan(value) || value == -kInfinity) {  // the message is built only on failure
      throw Error(std::string(function) + ": samples must be finite or +infinity, got " + std::to_string(value));
    }
  }
}

void check_size(int width, int height, std::size_t samples, const char* function) {
  check(width >= 0 && height >= 0, std::string(function) + ": negative grid size");
  const long long cells = static_cast<long long>(width) * height;
  check(cells <= kMaxDistanceTransformCells, std::string(function) + ": the grid has more than 2^28 cells");
  check(static_cast<long long>(samples) == cells,
        std::string(function) + ": expected " + std::to_string(cells) + " samples, got " + std::to_string(samples));
}

/// The 2D transform, first pass: the 1D transform of every column, written into `field` (and the
/// minimising row of each cell into `column_argmin` when not empty). Columns are copied in strips
/// of kStrip (a few cache lines per row) so that the strided reads and writes stay in cache.
void transform_columns(std::span<const double> f, SquaredDistanceField& field, std::vector<int>& column_argmin) {
  constexpr int kStrip = 16;
  const int w = field.width;
  const auto h = static_cast<std::size_t>(field.height);
  const bool nearest = !column_argmin.empty();
  std::vector<double> lines(kStrip * h);
  std::vector<double> results(kStrip * h);
  std::vector<int> args(nearest ? kStrip * h : 0);
  Envelope envelope(h);
  for (int x0 = 0; x0 < w; x0 += kStrip) {
    const int strip = std::min(kStrip, w - x0);
    for (std::size_t y = 0; y < h; ++y) {
      const double* row = f.data() + y * w + x0;
      for (int c = 0; c < strip; ++c) lines[c * h + y] = row[c];
    }
    for (int c = 0; c < strip; ++c) {
      lower_envelope_transform(lines.data() + c * h, static_cast<int>(h), results.data() + c * h,
                               nearest ? args.data() + c * h : nullptr, envelope);
    }
    for (std::size_t y = 0; y < h; ++y) {
      double* row = field.squared_distances.data() + y * w + x0;
      for (int c = 0; c < strip; ++c) row[c] = results[c * h + y];
      if (!nearest) continue;
      int* arg_row = column_argmin.data() + y * w + x0;
      for (int c = 0; c < strip; ++c) arg_row[c] = args[c * h + y];
    }
  }
}

/// The 2D transform, second pass: the 1D transform of every row of the column pass, in place; the nearest
/// site of (x, y) is then (x', column_argmin(x', y)) for the minimising column x'.
void transform_rows(SquaredDistanceField& field, const std::vector<int>& column_argmin) {
  const int w = field.width;
  const bool nearest = !column_argmin.empty();
  std::vector<double> line(static_cast<std::size_t>(w));
  std::vector<int> arg(nearest ? static_cast<std::size_t>(w) : 0);
  Envelope envelope(static_cast<std::size_t>(w));
  for (int y = 0; y < field.height; ++y) {
    double* row = field.squared_distances.data() + static_cast<std::size_t>(y) * w;
    std::copy(row, row + w, line.begin());
    lower_envelope_transform(line.data(), w, row, nearest ? arg.data() : nullptr, envelope);
    if (!nearest) continue;
    for (int x = 0; x < w; ++x) {
      const int column = arg[static_cast<std::size_t>(x)];
      const std::size_t base = static_cast<std::size_t>(y) * w;
      field.nearest_sites[base + x] = column < 0 ? -1 : column_argmin[base + column] * w + column;
    }
  }
}

}  // namespace

void distance_transform_1d(std::span<const double> f, std::span<double> out, std::span<int> argmin) {
  check(out.size() == f.size(), "distance_transform_1d: the output must have the input's size");
  check(argmin.empty() || argmin.size() == f.size(),
        "distance_transform_1d: argmin must be empty or of the input's size");
  check(f.size() <= static_cast<std::size_t>(kMaxDistanceTransformCells), "distance_transform_1d: too many samples");
  check_samples(f, "distance_transform_1d");
  Envelope envelope(f.size());
  lower_envelope_transform(f.data(), static_cast<int>(f.size()), out.data(), argmin.empty() ? nullptr : argmin.data(),
                           envelope);
}

SquaredDistanceField squared_distance_transform(int width, int height, std::span<const double> f, bool nearest_sites) {
  check_size(width, height, f.size(), "squared_distance_transform");
  check_samples(f, "squared_distance_transform");
  SquaredDistanceField field;
  field.width = width;
  field.height = height;
  field.squared_distances.resize(f.size());
  std::vector<int> column_argmin;
  if (nearest_sites) {
    column_argmin.resize(f.size());
    field.nearest_sites.resize(f.size());
  }
  transform_columns(f, field, column_argmin);
  transform_rows(field, column_argmin);
  return field;
}

SquaredDistanceField squared_distance_transform_of_sites(int width, int height, std::span<const std::uint8_t> sites,
                                                         bool nearest_sites) {
  check_size(width, height, sites.size(), "squared_distance_transform_of_sites");
  std::vector<double> f(sites.size());
  for (std::size_t i = 0; i < sites.size(); ++i) f[i] = sites[i] != 0 ? 0.0 : kInfinity;
  return squared_distance_transform(width, height, f, nearest_sites);
}

}  // namespace slam2d
