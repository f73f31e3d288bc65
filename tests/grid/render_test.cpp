// SPDX-License-Identifier: BSD-3-Clause
// render_map: cell colours, trajectory polyline and markers.

#include "slam2d/grid/render.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

Rgb pixel(const RgbImage& image, int col, int row) {
  const std::size_t i = 3 * (static_cast<std::size_t>(row) * image.width + col);
  return {image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]};
}

/// 10 x 6 cells of 1 m, all free but cell (9, 0) occupied, (0, 5) unknown and (4, 0) at 50 %.
OccupancyMap test_map() {
  OccupancyMap map;
  map.resolution = 1.0;
  map.width = 10;
  map.height = 6;
  map.cells.assign(60, OccupancyMap::kFree);
  map.at(9, 0) = OccupancyMap::kOccupied;
  map.at(0, 5) = OccupancyMap::kUnknown;
  map.at(4, 0) = 50;
  return map;
}

TEST(Render, CellsAreScaledBlocksWithRowZeroAtTheTop) {
  const RenderOptions options{.scale = 2};
  const RgbImage image = render_map(test_map(), {}, options);
  ASSERT_EQ(image.width, 20);
  ASSERT_EQ(image.height, 12);
  // Map row 0 is the bottom of the picture: cell (9, 0) covers columns 18-19, rows 10-11.
  for (int r = 10; r < 12; ++r) {
    for (int c = 18; c < 20; ++c) EXPECT_EQ(pixel(image, c, r), options.occupied_colour);
  }
  EXPECT_EQ(pixel(image, 17, 11), options.free_colour);
  EXPECT_EQ(pixel(image, 1, 1), options.unknown_colour);  // cell (0, 5), top-left
  EXPECT_EQ(pixel(image, 2, 1), options.free_colour);
  EXPECT_EQ(pixel(image, 8, 10), options.unknown_colour);  // 50 %: between the thresholds
  const RgbImage shaded = render_map(test_map(), {}, RenderOptions{.shaded = true});
  EXPECT_EQ(pixel(shaded, 4, 5), (Rgb{128, 128, 128}));  // 255 * (1 - 0.5) = 127.5 -> 128
  EXPECT_EQ(pixel(shaded, 9, 5), (Rgb{0, 0, 0}));
}

TEST(Render, DrawsTheTrajectoryWithStartAndEndMarkers) {
  const RenderOptions options{.scale = 2, .marker_radius = 1};
  // From (1.5, 3.5) to (8.5, 3.5): pixels (x * 2, (6 - y) * 2) = (3, 5) to (17, 5), then down to (8.5, 1.5) = (17, 9).
  const std::vector<SE2> trajectory{SE2(1.5, 3.5, 0.0), SE2(8.5, 3.5, 0.0), SE2(8.5, 1.5, -1.0)};
  const RgbImage image = render_map(test_map(), trajectory, options);
  for (int c = 5; c <= 15; ++c) EXPECT_EQ(pixel(image, c, 5), options.trajectory_colour) << c;
  for (int r = 5 + 2; r <= 9 - 2; ++r) EXPECT_EQ(pixel(image, 17, r), options.trajectory_colour) << r;
  EXPECT_EQ(pixel(image, 10, 4), options.free_colour);  // only one pixel wide
  EXPECT_EQ(pixel(image, 10, 6), options.free_colour);
  // Start disc (radius 1) around (3, 5), end disc around (17, 9).
  for (const auto& [dc, dr] : {std::pair{0, 0}, {1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
    EXPECT_EQ(pixel(image, 3 + dc, 5 + dr), options.start_colour);
    EXPECT_EQ(pixel(image, 17 + dc, 9 + dr), options.end_colour);
  }
  EXPECT_EQ(pixel(image, 4, 6), options.free_colour);  // the disc's corner is not painted
  // Count: every trajectory-coloured pixel lies on one of the two segments.
  for (int r = 0; r < image.height; ++r) {
    for (int c = 0; c < image.width; ++c) {
      if (pixel(image, c, r) == options.trajectory_colour) {
        EXPECT_TRUE(r == 5 || c == 17) << c << "," << r;
      }
    }
  }
}

TEST(Render, RotatedOriginAndClipping) {
  OccupancyMap map = test_map();
  map.origin = SE2(10.0, 0.0, std::numbers::pi / 2);  // map x along world y
  // World (9.5, 2.5) is map-local (2.5, 0.5): pixel (2.5, 5.5) at scale 1.
  const Eigen::Vector2d p = map_point_to_pixel(map, {9.5, 2.5}, 1);
  EXPECT_NEAR(p.x(), 2.5, 1e-12);
  EXPECT_NEAR(p.y(), 5.5, 1e-12);
  // A trajectory reaching far outside the picture is clipped.
  const std::vector<SE2> trajectory{SE2(9.5, 2.5, 0.0), SE2(9.5, 1e9, 0.0)};
  const RgbImage image = render_map(map, trajectory, RenderOptions{.marker_radius = 0});
  const RenderOptions defaults;
  EXPECT_EQ(pixel(image, 2, 5), defaults.start_colour);
  for (int c = 3; c < 10; ++c) EXPECT_EQ(pixel(image, c, 5), defaults.trajectory_colour) << c;
}

TEST(Render, CropsToTheKnownCellsAndThePathsWithAMargin) {
  // 100 x 80 cells of 0.1 m, unknown but for a 10 x 5 block of free cells at (40..49, 20..24).
  OccupancyMap map;
  map.resolution = 0.1;
  map.origin = SE2(-3.0, 2.0, 0.0);
  map.width = 100;
  map.height = 80;
  map.cells.assign(8000, OccupancyMap::kUnknown);
  for (int iy = 20; iy < 25; ++iy) {
    for (int ix = 40; ix < 50; ++ix) map.at(ix, iy) = OccupancyMap::kFree;
  }
  const RgbImage whole = render_map(map, {}, RenderOptions{.crop_margin = -1});
  EXPECT_EQ(whole.width, 100);
  const RgbImage cropped = render_map(map, {}, RenderOptions{.crop_margin = 3});
  EXPECT_EQ(cropped.width, 10 + 2 * 3);
  EXPECT_EQ(cropped.height, 5 + 2 * 3);
  const RenderOptions defaults;
  EXPECT_EQ(pixel(cropped, 3, 3), defaults.free_colour);  // the block's top-left cell (40, 24)
  EXPECT_EQ(pixel(cropped, 2, 3), defaults.unknown_colour);
  // A reference path reaching cell (70, 60) widens the box to it; drawn in its colour, as the
  // path is where it leaves the block's picture position unchanged.
  const Eigen::Vector2d far = map.origin.act(Eigen::Vector2d(70.5 * 0.1, 60.5 * 0.1));
  const Eigen::Vector2d near = map.origin.act(Eigen::Vector2d(45.5 * 0.1, 22.5 * 0.1));
  RenderOptions with_reference{.marker_radius = 0, .crop_margin = 0};
  with_reference.reference = {SE2(near.x(), near.y(), 0.0), SE2(far.x(), far.y(), 0.0)};
  const RgbImage widened = render_map(map, {}, with_reference);
  EXPECT_EQ(widened.width, 70 - 40 + 1);
  EXPECT_EQ(widened.height, 60 - 20 + 1);
  EXPECT_EQ(pixel(widened, 30, 0), with_reference.reference_colour);  // cell (70, 60): top right
  EXPECT_EQ(pixel(widened, 5, 60 - 22), with_reference.reference_colour);  // cell (45, 22)
  // crop_map keeps every cell where it was in the world.
  const OccupancyMap part = crop_map(map, 40, 20, 10, 5);
  EXPECT_EQ(part.at(0, 0), OccupancyMap::kFree);
  EXPECT_NEAR((part.origin.translation() - map.origin.act(Eigen::Vector2d(4.0, 2.0))).norm(), 0.0, 1e-12);
  EXPECT_THROW(crop_map(map, 95, 0, 10, 5), Error);
}

TEST(Render, TheScaleBarIsOneTwoOrFiveTimesAPowerOfTenAndAsLongAsItSays) {
  EXPECT_DOUBLE_EQ(scale_bar_length(400, 0.05), 5.0);   // a quarter: 5 m
  EXPECT_DOUBLE_EQ(scale_bar_length(400, 0.04), 2.0);   // a quarter is 4 m
  EXPECT_DOUBLE_EQ(scale_bar_length(1000, 0.1), 20.0);  // 25 m fits 20
  EXPECT_DOUBLE_EQ(scale_bar_length(100, 0.001), 0.02);
  EXPECT_EQ(scale_bar_length(0, 0.05), 0.0);
  // On a free map 400 x 200 cells of 0.05 m: a 5 m bar, 100 pixels of black along one row.
  OccupancyMap map;
  map.resolution = 0.05;
  map.width = 400;
  map.height = 200;
  map.cells.assign(80000, OccupancyMap::kFree);
  const RgbImage image = render_map(map, {}, RenderOptions{.scale_bar = true});
  int longest = 0;
  for (int r = image.height / 2; r < image.height; ++r) {
    int run = 0;
    for (int c = 0; c < image.width / 2; ++c) {
      run = pixel(image, c, r) == Rgb{0, 0, 0} ? run + 1 : 0;
      longest = std::max(longest, run);
    }
  }
  EXPECT_EQ(longest, 100);
  const RgbImage plain = render_map(map, {}, RenderOptions{});
  EXPECT_EQ(pixel(plain, 20, 190), (Rgb{255, 255, 255}));  // no bar unless asked
}

TEST(Render, LostStretchesPointsAndTheEndEllipse) {
  // test_map(): 10 x 6 cells of 1 m, scale 4. A path along y = 3.5 whose second segment is lost.
  RenderOptions options{.scale = 4, .marker_radius = 0};
  const std::vector<SE2> path{SE2(0.5, 3.5, 0.0), SE2(2.5, 3.5, 0.0), SE2(4.5, 3.5, 0.0), SE2(6.5, 3.5, 0.0)};
  options.lost = {false, false, true, false};  // segments 1-2 and 2-3 touch the lost pose
  options.points = {Eigen::Vector2d(8.5, 1.5)};
  options.end_covariance = Eigen::Vector2d(0.25, 0.0625).asDiagonal();  // sigma 0.5 m along x, 0.25 m along y
  const RgbImage image = render_map(test_map(), path, options);
  const int row = (6 * 4) - static_cast<int>(3.5 * 4);  // picture row of y = 3.5
  EXPECT_EQ(pixel(image, 6, row), options.trajectory_colour);   // x = 1.5: the first segment
  EXPECT_EQ(pixel(image, 14, row), options.lost_colour);        // x = 3.5
  EXPECT_EQ(pixel(image, 20, row), options.lost_colour);        // x = 5.0
  EXPECT_EQ(pixel(image, 34, 18), options.points_colour);       // (8.5, 1.5): pixel (34, 18)
  // The 2-sigma ellipse around (6.5, 3.5), pixel (26, row): 1 m = 4 pixels either side along x,
  // 0.5 m = 2 along y, and nothing beyond.
  EXPECT_EQ(pixel(image, 26 + 4, row), options.end_colour);
  EXPECT_EQ(pixel(image, 26 + 5, row), options.free_colour);
  EXPECT_EQ(pixel(image, 26, row - 2), options.end_colour);
  EXPECT_EQ(pixel(image, 26, row + 2), options.end_colour);
  EXPECT_EQ(pixel(image, 26, row - 4), options.free_colour);
  EXPECT_THROW(render_map(test_map(), path, RenderOptions{.lost = {true}}), Error);
}

TEST(Render, RejectsBadOptions) {
  EXPECT_THROW(render_map(test_map(), {}, RenderOptions{.scale = 0}), Error);
  OccupancyMap broken = test_map();
  broken.cells.pop_back();
  EXPECT_THROW(render_map(broken, {}), Error);
  EXPECT_THROW(render_map(test_map(), {SE2(), SE2(std::nan(""), 0.0, 0.0)}), Error);
  EXPECT_EQ(render_map(OccupancyMap{}, {SE2()}).width, 0);
}

}  // namespace
}  // namespace slam2d
