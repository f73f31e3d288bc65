// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Exact squared Euclidean distance transform in linear time: P. Felzenszwalb and D. Huttenlocher,
// "Distance Transforms of Sampled Functions", Theory of Computing 8, 2012.
//
// The 1D transform d(q) = min_p ((q - p)^2 + f(p)) is the lower envelope of the parabolas rooted
// at the samples (the paper's Algorithm DT(f)); the 2D transform applies it one dimension at a
// time, to every column, then to every row of the result. Both passes are O(n), so the whole transform
// is O(width * height). Distances are in cells; cell (x, y) sits at (x, y), so a grid of sites
// gives each cell the squared distance between its centre and the nearest site's centre.

#include <cstdint>
#include <span>
#include <vector>

namespace slam2d {

/// A dense raster of squared distances (cells^2), row-major: cell (x, y) at index y * width + x.
struct SquaredDistanceField {
  int width = 0;
  int height = 0;
  std::vector<double> squared_distances;  // cells^2; +infinity where no site (or finite sample) exists
  std::vector<int> nearest_sites;         // index y * width + x of a nearest site, -1 when none;
                                          // empty unless asked for

  double at(int x, int y) const { return squared_distances[static_cast<std::size_t>(y) * width + x]; }
  int nearest_site(int x, int y) const { return nearest_sites[static_cast<std::size_t>(y) * width + x]; }
};

/// Largest number of cells the transforms accept (2^28), far above any map of the project.
inline constexpr long long kMaxDistanceTransformCells = 1LL << 28;

/// The 1D transform of Algorithm DT(f): out[q] = min_p ((q - p)^2 + f[p]). Samples with
/// f[p] = +infinity carry no parabola; when every sample is infinite, every output is infinite.
/// `argmin`, if not empty, receives for each q a minimising p (-1 when none). `out` and `argmin`
/// must have f's size. Throws Error for a size mismatch or a NaN or -infinity sample.
void distance_transform_1d(std::span<const double> f, std::span<double> out, std::span<int> argmin = {});

/// The 2D transform of a sampled function (columns, then rows): at each cell, min over cells p of
/// |cell - p|^2 + f[p]. Samples are row-major (index y * width + x) and may be +infinity (no
/// site); finite samples act as sites with an offset. With `nearest_sites`, also the index of a
/// minimising cell. Throws Error for negative sizes, more than kMaxDistanceTransformCells cells,
/// a sample count other than width * height, or a NaN or -infinity sample.
SquaredDistanceField squared_distance_transform(int width, int height, std::span<const double> f,
                                                bool nearest_sites = false);

/// The squared Euclidean distance transform of a binary grid: a cell is a site when its value is
/// not zero. An empty grid (no site) gives +infinity everywhere. Errors as above.
SquaredDistanceField squared_distance_transform_of_sites(int width, int height, std::span<const std::uint8_t> sites,
                                                         bool nearest_sites = false);

}  // namespace slam2d
