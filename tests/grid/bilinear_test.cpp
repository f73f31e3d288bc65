// SPDX-License-Identifier: BSD-3-Clause
// Bilinear interpolation of Kohlbrecher et al. 2011, Eq. (4)-(6): exact at cell centres,
// continuous across cells, exact on linear fields, gradient equal to finite differences of the
// interpolated value, and the occupancy-grid fast path equal to the generic one.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/grid/bilinear.hpp"
#include "slam2d/grid/occupancy_grid.hpp"

namespace slam2d {
namespace {

// An arbitrary, non-smooth cell field.
double field(CellIndex c) { return std::sin(0.7 * c.x) + std::cos(1.3 * c.y) + 0.01 * c.x * c.y; }

GridGeometry geometry() {
  GridGeometry g;
  g.resolution = 0.1;
  g.origin = Eigen::Vector2d(-1.05, 0.3);
  return g;
}

TEST(Bilinear, ExactAtCellCentres) {
  const GridGeometry g = geometry();
  for (int x = -5; x <= 5; ++x) {
    for (int y = -4; y <= 6; ++y) {
      const BilinearSample s = interpolate_bilinear(g, field, g.cell_center({x, y}));
      EXPECT_NEAR(s.value, field({x, y}), 1e-12) << x << " " << y;
    }
  }
}

TEST(Bilinear, ContinuousAcrossCellBoundaries) {
  const GridGeometry g = geometry();
  const double eps = 1e-9;
  // Across the lines joining cell centres (where the square changes) and across cell edges.
  for (int k = -3; k <= 3; ++k) {
    const Eigen::Vector2d on_centre_line(g.cell_center({k, 0}).x(), g.origin.y() + 0.237);
    const Eigen::Vector2d on_edge(g.cell_corner({k, 0}).x(), g.origin.y() + 0.237);
    for (const Eigen::Vector2d& p : {on_centre_line, on_edge}) {
      const double left = interpolate_bilinear(g, field, p - Eigen::Vector2d(eps, 0)).value;
      const double right = interpolate_bilinear(g, field, p + Eigen::Vector2d(eps, 0)).value;
      EXPECT_NEAR(left, right, 1e-7);
      const double below = interpolate_bilinear(g, field, p - Eigen::Vector2d(0, eps)).value;
      const double above = interpolate_bilinear(g, field, p + Eigen::Vector2d(0, eps)).value;
      EXPECT_NEAR(below, above, 1e-7);
    }
  }
}

TEST(Bilinear, ReproducesLinearFieldsAndTheirGradient) {
  const GridGeometry g = geometry();
  // A linear function of the cell centre position: interpolation must give it back exactly.
  const Eigen::Vector2d slope(0.8, -2.5);
  const auto linear = [&](CellIndex c) { return 3.0 + slope.dot(g.cell_center(c)); };
  Rng rng(7);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d p(rng.uniform(-2.0, 2.0), rng.uniform(-1.0, 3.0));
    const BilinearSample s = interpolate_bilinear(g, linear, p);
    EXPECT_NEAR(s.value, 3.0 + slope.dot(p), 1e-10);
    EXPECT_NEAR(s.gradient.x(), slope.x(), 1e-9);
    EXPECT_NEAR(s.gradient.y(), slope.y(), 1e-9);
  }
}

TEST(Bilinear, GradientMatchesFiniteDifferences) {
  const GridGeometry g = geometry();
  Rng rng(3);
  const double h = 1e-6;
  int checked = 0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector2d p(rng.uniform(-2.0, 2.0), rng.uniform(-1.0, 3.0));
    const BilinearCorner c = bilinear_corner(g, p);
    // Eq. (5)-(6) is the derivative inside a square: stay clear of its borders.
    if ((c.fraction.array() < 1e-3).any() || (c.fraction.array() > 1.0 - 1e-3).any()) continue;
    const BilinearSample s = interpolate_bilinear(g, field, p);
    const double dx = (interpolate_bilinear(g, field, p + Eigen::Vector2d(h, 0)).value -
                       interpolate_bilinear(g, field, p - Eigen::Vector2d(h, 0)).value) / (2 * h);
    const double dy = (interpolate_bilinear(g, field, p + Eigen::Vector2d(0, h)).value -
                       interpolate_bilinear(g, field, p - Eigen::Vector2d(0, h)).value) / (2 * h);
    EXPECT_NEAR(s.gradient.x(), dx, 1e-5);
    EXPECT_NEAR(s.gradient.y(), dy, 1e-5);
    ++checked;
  }
  EXPECT_GT(checked, 450);
}

TEST(Bilinear, HandComputedSquare) {
  // Centres at (0.5, 0.5), (1.5, 0.5), (0.5, 1.5), (1.5, 1.5) with values 0, 1, 2, 4 (resolution 1).
  GridGeometry g;
  g.resolution = 1.0;
  const auto values = [](CellIndex c) { return c == CellIndex{0, 0} ? 0.0 : c == CellIndex{1, 0} ? 1.0 : c == CellIndex{0, 1} ? 2.0 : 4.0; };
  const BilinearSample s = interpolate_bilinear(g, values, Eigen::Vector2d(0.75, 1.0));  // fx = 0.25, fy = 0.5
  EXPECT_DOUBLE_EQ(s.value, 0.5 * (0.75 * 0 + 0.25 * 1) + 0.5 * (0.75 * 2 + 0.25 * 4));
  EXPECT_DOUBLE_EQ(s.gradient.x(), 0.5 * 1 + 0.5 * 2);
  EXPECT_DOUBLE_EQ(s.gradient.y(), 0.75 * 2 + 0.25 * 3);
}

TEST(Bilinear, OccupancyFastPathEqualsGenericPath) {
  OccupancyGrid grid(OccupancyGridConfig{.resolution = 0.05});
  LaserScan scan;
  scan.angle_min = -std::numbers::pi / 2;
  scan.angle_increment = std::numbers::pi / 180;
  scan.range_max = 30.0;
  for (int i = 0; i < 180; ++i) scan.ranges.push_back(2.0 + 0.5 * std::sin(0.1 * i));
  grid.integrate_scan(scan, SE2(0.3, -0.2, 0.4));
  grid.integrate_scan(scan, SE2(0.5, -0.1, 0.45));
  const auto probability = [&](CellIndex c) { return grid.probability(c); };
  Rng rng(11);
  for (int i = 0; i < 2000; ++i) {
    // Points around the scanned area, including tile borders (multiples of 64 cells = 3.2 m).
    const Eigen::Vector2d p(rng.uniform(-3.3, 3.3), rng.uniform(-3.3, 3.3));
    const BilinearSample fast = interpolate_occupancy(grid, p);
    const BilinearSample generic = interpolate_bilinear(grid.geometry(), probability, p);
    EXPECT_NEAR(fast.value, generic.value, 1e-6);  // the fast path computes P in single precision
    EXPECT_NEAR((fast.gradient - generic.gradient).norm(), 0.0, 1e-4);
  }
  // Unknown space reads 0.5, flat.
  const BilinearSample far = interpolate_occupancy(grid, Eigen::Vector2d(50.0, 50.0));
  EXPECT_EQ(far.value, 0.5);
  EXPECT_EQ(far.gradient, Eigen::Vector2d::Zero());
  EXPECT_EQ(interpolate_occupancy(grid, Eigen::Vector2d(NAN, 0.0)).value, 0.5);
  EXPECT_EQ(interpolate_occupancy(grid, Eigen::Vector2d(1e300, 0.0)).value, 0.5);
}

TEST(Bilinear, InterpolatorGivesInterpolateOccupancyBitForBit) {
  OccupancyGrid grid(OccupancyGridConfig{.resolution = 0.05, .probability_hit = 0.9, .probability_miss = 0.44});
  LaserScan scan;
  scan.angle_min = -std::numbers::pi / 2;
  scan.angle_increment = std::numbers::pi / 180;
  scan.range_max = 30.0;
  for (int i = 0; i < 180; ++i) scan.ranges.push_back(2.0 + 0.5 * std::sin(0.1 * i));
  for (int k = 0; k < 12; ++k) grid.integrate_scan(scan, SE2(0.3 + 0.05 * k, -0.2, 0.4 + 0.02 * k));  // clamped cells too
  OccupancyInterpolator interpolate(grid);
  Rng rng(12);
  for (int i = 0; i < 20000; ++i) {
    // Around the scanned area (tile borders at multiples of 3.2 m), and now and then far beyond the index range.
    const Eigen::Vector2d p = i % 1000 == 0 ? Eigen::Vector2d(rng.uniform(-1e9, 1e9), rng.uniform(-1e9, 1e9))
                                            : Eigen::Vector2d(rng.uniform(-3.4, 3.4), rng.uniform(-3.4, 3.4));
    const BilinearSample expected = interpolate_occupancy(grid, p);
    const BilinearSample got = interpolate(p);
    ASSERT_EQ(got.value, expected.value) << i;
    ASSERT_EQ(got.gradient.x(), expected.gradient.x()) << i;
    ASSERT_EQ(got.gradient.y(), expected.gradient.y()) << i;
  }
  EXPECT_EQ(interpolate(Eigen::Vector2d(NAN, 0.0)).value, 0.5);
}

}  // namespace
}  // namespace slam2d
