// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/render.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/grid/ray_casting.hpp"

namespace slam2d {

namespace {

Rgb cell_colour(std::int8_t value, const RenderOptions& options) {
  if (value < 0 || value > 100) return options.unknown_colour;
  if (options.shaded) {
    const auto grey = static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - value / 100.0)));
    return {grey, grey, grey};
  }
  if (value > options.occupied_threshold) return options.occupied_colour;
  if (value < options.free_threshold) return options.free_colour;
  return options.unknown_colour;
}

void paint(RgbImage& image, int col, int row, const Rgb& colour) { image.set(col, row, colour[0], colour[1], colour[2]); }

void draw_cells(RgbImage& image, const OccupancyMap& map, const RenderOptions& options) {
  const int s = options.scale;
  for (int iy = 0; iy < map.height; ++iy) {
    const int top = (map.height - 1 - iy) * s;
    for (int ix = 0; ix < map.width; ++ix) {
      const Rgb colour = cell_colour(map.at(ix, iy), options);
      for (int r = top; r < top + s; ++r) {
        for (int c = ix * s; c < ix * s + s; ++c) paint(image, c, r, colour);
      }
    }
  }
}

/// Liang-Barsky clipping of the segment a-b to the box [low, high]^2; false when it misses.
bool clip_segment(Eigen::Vector2d& a, Eigen::Vector2d& b, const Eigen::Vector2d& low, const Eigen::Vector2d& high) {
  const Eigen::Vector2d d = b - a;
  double t0 = 0.0;
  double t1 = 1.0;
  for (int axis = 0; axis < 2; ++axis) {
    const double p[2] = {-d[axis], d[axis]};
    const double q[2] = {a[axis] - low[axis], high[axis] - a[axis]};
    for (int k = 0; k < 2; ++k) {
      if (p[k] == 0.0) {
        if (q[k] < 0.0) return false;
        continue;
      }
      const double t = q[k] / p[k];
      if (p[k] < 0.0) t0 = std::max(t0, t);
      else t1 = std::min(t1, t);
    }
  }
  if (t0 > t1) return false;
  const Eigen::Vector2d start = a;
  a = start + t0 * d;
  b = start + t1 * d;
  return true;
}

CellIndex pixel_of(const Eigen::Vector2d& p) {
  return {static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y()))};
}

void draw_polyline(RgbImage& image, const std::vector<Eigen::Vector2d>& pixels, const Rgb& colour) {
  const Eigen::Vector2d low(0.0, 0.0);
  const Eigen::Vector2d high(image.width - 1e-9, image.height - 1e-9);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (i + 1 == pixels.size() && i > 0) break;  // the last point ends the previous segment
    Eigen::Vector2d a = pixels[i];
    Eigen::Vector2d b = pixels[std::min(i + 1, pixels.size() - 1)];
    if (!clip_segment(a, b, low, high)) continue;
    const CellIndex to = pixel_of(b);
    for_each_cell_before(pixel_of(a), to, [&](CellIndex p) { paint(image, p.x, p.y, colour); });
    paint(image, to.x, to.y, colour);
  }
}

void draw_disc(RgbImage& image, const Eigen::Vector2d& centre, int radius, const Rgb& colour) {
  const CellIndex c = pixel_of(centre.cwiseMax(-1e6).cwiseMin(1e6));
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      if (dx * dx + dy * dy <= radius * radius) paint(image, c.x + dx, c.y + dy, colour);
    }
  }
}

}  // namespace

Eigen::Vector2d map_point_to_pixel(const OccupancyMap& map, const Eigen::Vector2d& point, int scale) {
  const Eigen::Vector2d local = map.origin.inverse().act(point) / map.resolution;  // in cells
  return {local.x() * scale, (map.height - local.y()) * scale};
}

RgbImage render_map(const OccupancyMap& map, const std::vector<SE2>& trajectory, const RenderOptions& options) {
  check(options.scale >= 1 && options.scale <= 64, "render_map: scale must lie in [1, 64]");
  check(options.marker_radius >= 0 && options.marker_radius <= 1000, "render_map: marker_radius must lie in [0, 1000]");
  check(map.width >= 0 && map.height >= 0 &&
            static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height) == map.cells.size(),
        "render_map: map size does not match its cells");
  check(std::isfinite(map.resolution) && map.resolution > 0.0 && map.origin.vector().allFinite(),
        "render_map: map resolution or origin invalid");
  const long long pixels = static_cast<long long>(map.width) * map.height * options.scale * options.scale;
  check(pixels <= (1LL << 28), "render_map: the picture would exceed 2^28 pixels");
  RgbImage image(map.width * options.scale, map.height * options.scale);
  draw_cells(image, map, options);
  std::vector<Eigen::Vector2d> path;
  path.reserve(trajectory.size());
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    check(trajectory[i].translation().allFinite(), "render_map: trajectory pose " + std::to_string(i) + " is not finite");
    path.push_back(map_point_to_pixel(map, trajectory[i].translation(), options.scale));
  }
  if (path.empty() || image.width == 0 || image.height == 0) return image;
  draw_polyline(image, path, options.trajectory_colour);
  draw_disc(image, path.front(), options.marker_radius, options.start_colour);
  draw_disc(image, path.back(), options.marker_radius, options.end_colour);
  return image;
}

}  // namespace slam2d
