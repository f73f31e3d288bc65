// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Rendering of an occupancy map and a trajectory as an RGB picture (the CLI's map.png).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

using Rgb = std::array<std::uint8_t, 3>;

struct RenderOptions {
  int scale = 1;                      // output pixels per map cell, in [1, 64]
  bool shaded = false;                // true: grey level follows occupancy; false: three colours
  double occupied_threshold = 65.0;   // %, cells above are occupied (when not shaded), as map_saver
  double free_threshold = 19.6;       // %, cells below are free (when not shaded)
  Rgb occupied_colour{0, 0, 0};
  Rgb free_colour{255, 255, 255};
  Rgb unknown_colour{205, 205, 205};  // also the band between the thresholds
  Rgb trajectory_colour{220, 30, 30};
  Rgb start_colour{0, 170, 0};        // filled disc at the first pose
  Rgb end_colour{30, 60, 220};        // filled disc at the last pose
  int marker_radius = 3;              // pixels, >= 0
  std::vector<SE2> reference{};       // map-frame poses drawn under the trajectory (e.g. ground truth); may be empty
  Rgb reference_colour{0, 160, 210};
  std::vector<bool> lost{};           // empty, or one per trajectory pose: a segment touching a lost pose is lost_colour
  Rgb lost_colour{255, 140, 0};
  std::vector<Eigen::Vector2d> points{};   // map-frame points drawn as single pixels (e.g. a particle filter's particles)
  Rgb points_colour{150, 0, 170};
  Eigen::Matrix2d end_covariance = Eigen::Matrix2d::Zero();  // m^2 of the last pose; non-zero: its 2-sigma ellipse is drawn
  int crop_margin = -1;               // cells; >= 0: the picture is cropped to the known cells and both paths, plus this
  bool scale_bar = false;             // a scale bar with its length in metres at the bottom left
};

/// The map as an RGB image, row 0 at the top (map row height - 1), each cell a scale x scale
/// block: occupied black, free white, unknown grey (or, shaded, a grey level 255 (1 - v / 100)).
/// The trajectory (map-frame poses) is drawn on it as a one-pixel polyline (Bresenham), clipped to
/// the picture, with discs at its start and end; a reference path, if given, under it in its own
/// colour. Segments that touch a pose flagged in `lost` are drawn in lost_colour; `points` as
/// single pixels; a non-zero end_covariance as the 2-sigma ellipse around the last pose. With crop_margin >= 0 the picture covers only the bounding box of the known cells and
/// of both paths, widened by the margin (and clipped to the map). The scale bar is the longest of
/// 1, 2 or 5 times a power of ten metres that fits a quarter of the picture's width, labelled in
/// metres. Throws Error for a non-finite pose, a scale outside [1, 64], a map whose cells do not
/// match its size, or a picture over 2^28 pixels.
RgbImage render_map(const OccupancyMap& map, const std::vector<SE2>& trajectory, const RenderOptions& options = {});

/// The picture pixel (column, row) holding a map-frame point, in continuous coordinates: the
/// pixel is (floor(column), floor(row)).
Eigen::Vector2d map_point_to_pixel(const OccupancyMap& map, const Eigen::Vector2d& point, int scale);

/// The cells [x0, x0 + width) x [y0, y0 + height) of a map as a map of their own (its origin moved
/// to cell (x0, y0)); the box must lie within the map.
OccupancyMap crop_map(const OccupancyMap& map, int x0, int y0, int width, int height);
/// The map cropped to its known cells and the paths' cells, widened by `margin` cells; the map
/// itself when nothing is known and no path is given.
OccupancyMap crop_to_content(const OccupancyMap& map, int margin, const std::vector<SE2>& trajectory = {},
                             const std::vector<SE2>& reference = {});

/// The length (m) of the scale bar render_map draws on a picture `pixels` wide at `metres_per_pixel`.
double scale_bar_length(int pixels, double metres_per_pixel);

}  // namespace slam2d
