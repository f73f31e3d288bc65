// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/grid/render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <string_view>

#include <Eigen/Eigenvalues>

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

/// The 2-sigma ellipse of a 2x2 covariance (m^2) around `centre` (pixels), `pixels_per_metre`.
void draw_ellipse(RgbImage& image, const Eigen::Vector2d& centre, const Eigen::Matrix2d& covariance,
                  double pixels_per_metre, const Rgb& colour) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(0.5 * (covariance + covariance.transpose()));
  const Eigen::Vector2d radii = 2.0 * solver.eigenvalues().cwiseMax(0.0).cwiseSqrt() * pixels_per_metre;
  if (!radii.allFinite() || radii.maxCoeff() > 1e5) return;
  const Eigen::Matrix2d axes = solver.eigenvectors();
  std::vector<Eigen::Vector2d> outline;
  constexpr int kSteps = 72;
  for (int k = 0; k <= kSteps; ++k) {
    const double a = 2.0 * std::numbers::pi * k / kSteps;
    const Eigen::Vector2d metric = axes * Eigen::Vector2d(radii.x() * std::cos(a), radii.y() * std::sin(a));
    outline.push_back(centre + Eigen::Vector2d(metric.x(), -metric.y()));  // picture rows grow downwards
  }
  draw_polyline(image, outline, colour);
}

void draw_disc(RgbImage& image, const Eigen::Vector2d& centre, int radius, const Rgb& colour) {
  const CellIndex c = pixel_of(centre.cwiseMax(-1e6).cwiseMin(1e6));
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      if (dx * dx + dy * dy <= radius * radius) paint(image, c.x + dx, c.y + dy, colour);
    }
  }
}

// A 5-row bitmap font for the scale bar's label: '#' is ink.
struct Glyph {
  char character;
  std::array<std::string_view, 5> rows;
};
constexpr std::array<Glyph, 12> kGlyphs{{
    {'0', {"###", "#.#", "#.#", "#.#", "###"}}, {'1', {".#.", "##.", ".#.", ".#.", "###"}},
    {'2', {"###", "..#", "###", "#..", "###"}}, {'3', {"###", "..#", "###", "..#", "###"}},
    {'4', {"#.#", "#.#", "###", "..#", "..#"}}, {'5', {"###", "#..", "###", "..#", "###"}},
    {'6', {"###", "#..", "###", "#.#", "###"}}, {'7', {"###", "..#", "..#", "..#", "..#"}},
    {'8', {"###", "#.#", "###", "#.#", "###"}}, {'9', {"###", "#.#", "###", "..#", "###"}},
    {'.', {".", ".", ".", ".", "#"}},           {'m', {".....", ".....", "####.", "#.#.#", "#.#.#"}},
}};

void fill_box(RgbImage& image, int col, int row, int width, int height, const Rgb& colour) {
  for (int r = row; r < row + height; ++r) {
    for (int c = col; c < col + width; ++c) paint(image, c, r, colour);
  }
}

/// Draws `text` with its top-left corner at (col, row), each font pixel a size x size block, on a
/// white box one font pixel wider all round; returns the width drawn (pixels).
int draw_text(RgbImage& image, std::string_view text, int col, int row, int size) {
  int width = 0;
  for (const char character : text) {
    for (const Glyph& glyph : kGlyphs) {
      if (glyph.character == character) width += static_cast<int>(glyph.rows[0].size() + 1) * size;
    }
  }
  fill_box(image, col - size, row - size, width + size, 7 * size, {255, 255, 255});
  int x = col;
  for (const char character : text) {
    for (const Glyph& glyph : kGlyphs) {
      if (glyph.character != character) continue;
      for (int r = 0; r < 5; ++r) {
        for (std::size_t c = 0; c < glyph.rows[r].size(); ++c) {
          if (glyph.rows[r][c] == '#') fill_box(image, x + static_cast<int>(c) * size, row + r * size, size, size, {0, 0, 0});
        }
      }
      x += static_cast<int>(glyph.rows[0].size() + 1) * size;
    }
  }
  return width;
}

void draw_scale_bar(RgbImage& image, double metres_per_pixel) {
  if (image.width < 60 || image.height < 40) return;
  const double length = scale_bar_length(image.width, metres_per_pixel);
  if (length <= 0.0) return;
  const int size = std::max(2, image.width / 400);  // font pixel and bar thickness unit
  const int pixels = static_cast<int>(std::lround(length / metres_per_pixel));
  const int left = 8 * size;
  const int bottom = image.height - 8 * size;
  const int thickness = 2 * size;
  fill_box(image, left - size, bottom - 4 * thickness - size, pixels + 2 * size, 4 * thickness + 2 * size, {255, 255, 255});
  fill_box(image, left, bottom - thickness, pixels, thickness, {0, 0, 0});
  fill_box(image, left, bottom - 4 * thickness, size, 4 * thickness, {0, 0, 0});
  fill_box(image, left + pixels - size, bottom - 4 * thickness, size, 4 * thickness, {0, 0, 0});
  char label[32];
  std::snprintf(label, sizeof label, "%gm", length);
  draw_text(image, label, left, bottom - 4 * thickness - 8 * size, size);
}

/// A map-frame point in continuous cell coordinates (x right, y up, cell (0, 0) from 0 to 1).
Eigen::Vector2d cell_coordinates(const OccupancyMap& map, const Eigen::Vector2d& point) {
  return map.origin.inverse().act(point) / map.resolution;
}

/// The cell holding a map-frame point (may lie outside the map).
CellIndex cell_of(const OccupancyMap& map, const Eigen::Vector2d& point) {
  const Eigen::Vector2d local = cell_coordinates(map, point);
  return {static_cast<int>(std::floor(std::clamp(local.x(), -1e9, 1e9))),
          static_cast<int>(std::floor(std::clamp(local.y(), -1e9, 1e9)))};
}

}  // namespace

OccupancyMap crop_to_content(const OccupancyMap& map, int margin, const std::vector<SE2>& trajectory,
                             const std::vector<SE2>& reference) {
  int x_min = map.width;
  int y_min = map.height;
  int x_max = -1;
  int y_max = -1;
  const auto extend = [&](int x, int y) {
    x_min = std::min(x_min, x);
    y_min = std::min(y_min, y);
    x_max = std::max(x_max, x);
    y_max = std::max(y_max, y);
  };
  for (int iy = 0; iy < map.height; ++iy) {
    for (int ix = 0; ix < map.width; ++ix) {
      if (map.at(ix, iy) != OccupancyMap::kUnknown) extend(ix, iy);
    }
  }
  for (const std::vector<SE2>* path : {&trajectory, &reference}) {
    for (const SE2& pose : *path) {
      const CellIndex c = cell_of(map, pose.translation());
      extend(std::clamp(c.x, 0, map.width - 1), std::clamp(c.y, 0, map.height - 1));
    }
  }
  if (x_max < 0) return map;
  x_min = std::max(0, x_min - margin);
  y_min = std::max(0, y_min - margin);
  x_max = std::min(map.width - 1, x_max + margin);
  y_max = std::min(map.height - 1, y_max + margin);
  return crop_map(map, x_min, y_min, x_max - x_min + 1, y_max - y_min + 1);
}

namespace {

std::vector<Eigen::Vector2d> pixels_of(const OccupancyMap& map, const std::vector<SE2>& poses, int scale,
                                       const char* name) {
  std::vector<Eigen::Vector2d> path;
  path.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    check(poses[i].translation().allFinite(), std::string("render_map: ") + name + " pose " + std::to_string(i) + " is not finite");
    path.push_back(map_point_to_pixel(map, poses[i].translation(), scale));
  }
  return path;
}

}  // namespace

OccupancyMap crop_map(const OccupancyMap& map, int x0, int y0, int width, int height) {
  check(x0 >= 0 && y0 >= 0 && width >= 0 && height >= 0 && x0 + width <= map.width && y0 + height <= map.height,
        "crop_map: the box does not lie within the map");
  OccupancyMap out;
  out.resolution = map.resolution;
  out.origin = map.origin * SE2(x0 * map.resolution, y0 * map.resolution, 0.0);
  out.width = width;
  out.height = height;
  out.cells.reserve(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int iy = y0; iy < y0 + height; ++iy) {
    for (int ix = x0; ix < x0 + width; ++ix) out.cells.push_back(map.at(ix, iy));
  }
  return out;
}

double scale_bar_length(int pixels, double metres_per_pixel) {
  if (pixels <= 0 || !(metres_per_pixel > 0.0) || !std::isfinite(metres_per_pixel)) return 0.0;
  const double fits = 0.25 * pixels * metres_per_pixel;
  double best = 0.0;
  for (int exponent = -3; exponent <= 6; ++exponent) {
    for (const double mantissa : {1.0, 2.0, 5.0}) {
      const double length = mantissa * std::pow(10.0, exponent);
      if (length <= fits) best = length;
    }
  }
  return best;
}

Eigen::Vector2d map_point_to_pixel(const OccupancyMap& map, const Eigen::Vector2d& point, int scale) {
  const Eigen::Vector2d local = cell_coordinates(map, point);
  return {local.x() * scale, (map.height - local.y()) * scale};
}

RgbImage render_map(const OccupancyMap& full_map, const std::vector<SE2>& trajectory, const RenderOptions& options) {
  check(options.scale >= 1 && options.scale <= 64, "render_map: scale must lie in [1, 64]");
  check(options.marker_radius >= 0 && options.marker_radius <= 1000, "render_map: marker_radius must lie in [0, 1000]");
  check(full_map.width >= 0 && full_map.height >= 0 &&
            static_cast<std::size_t>(full_map.width) * static_cast<std::size_t>(full_map.height) == full_map.cells.size(),
        "render_map: map size does not match its cells");
  check(std::isfinite(full_map.resolution) && full_map.resolution > 0.0 && full_map.origin.vector().allFinite(),
        "render_map: map resolution or origin invalid");
  const OccupancyMap map =
      options.crop_margin >= 0 ? crop_to_content(full_map, options.crop_margin, trajectory, options.reference) : full_map;
  const long long pixels = static_cast<long long>(map.width) * map.height * options.scale * options.scale;
  check(pixels <= (1LL << 28), "render_map: the picture would exceed 2^28 pixels");
  RgbImage image(map.width * options.scale, map.height * options.scale);
  draw_cells(image, map, options);
  const std::vector<Eigen::Vector2d> reference = pixels_of(map, options.reference, options.scale, "reference");
  const std::vector<Eigen::Vector2d> path = pixels_of(map, trajectory, options.scale, "trajectory");
  if (image.width == 0 || image.height == 0) return image;
  if (!reference.empty()) draw_polyline(image, reference, options.reference_colour);
  for (const Eigen::Vector2d& point : options.points) {
    if (!point.allFinite()) continue;
    const CellIndex p = pixel_of(map_point_to_pixel(map, point, options.scale).cwiseMax(-1e6).cwiseMin(1e6));
    paint(image, p.x, p.y, options.points_colour);
  }
  if (!path.empty()) {
    draw_polyline(image, path, options.trajectory_colour);
    check(options.lost.empty() || options.lost.size() == path.size(), "render_map: lost must be empty or one per trajectory pose");
    for (std::size_t i = 0; i + 1 < options.lost.size(); ++i) {
      if (options.lost[i] || options.lost[i + 1]) draw_polyline(image, {path[i], path[i + 1]}, options.lost_colour);
    }
    if (!options.end_covariance.isZero()) {
      const Eigen::Matrix2d R = map.origin.rotation();  // the covariance in the grid's axes
      draw_ellipse(image, path.back(), R.transpose() * options.end_covariance * R, options.scale / map.resolution,
                   options.end_colour);
    }
    draw_disc(image, path.front(), options.marker_radius, options.start_colour);
    draw_disc(image, path.back(), options.marker_radius, options.end_colour);
  }
  if (options.scale_bar) draw_scale_bar(image, map.resolution / options.scale);
  return image;
}

}  // namespace slam2d
