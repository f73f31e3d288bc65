// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/ray_caster.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kBucketMargin = 1e-6;  // m, walls on a cell border go into both cells
constexpr double kMaxCells = 1e7;       // grid cells, a bound on memory

double cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); }

/// The cell (0 .. n-1) along one axis that holds `coordinate`, clamped before the integer cast.
int cell_index(double coordinate, double grid_min, double cell_size, int n) {
  return static_cast<int>(std::clamp(std::floor((coordinate - grid_min) / cell_size), 0.0, n - 1.0));
}

}  // namespace

std::optional<double> intersect_ray_segment(const Eigen::Vector2d& origin, const Eigen::Vector2d& direction,
                                            const WallSegment& wall) {
  // origin + t * direction = a + u * (b - a), solved with 2D cross products.
  const Eigen::Vector2d edge = wall.b - wall.a;
  const double denominator = cross(direction, edge);
  if (denominator == 0.0) return std::nullopt;
  const Eigen::Vector2d w = wall.a - origin;
  const double t = cross(w, edge) / denominator;
  const double u = cross(w, direction) / denominator;
  if (!(t >= 0.0) || !(u >= 0.0) || !(u <= 1.0)) return std::nullopt;
  return t;
}

RayCaster::RayCaster(const World& world, double cell_size) : walls_(world.walls), cell_size_(cell_size) {
  check(std::isfinite(cell_size) && cell_size > 0.0, "RayCaster: cell size must be positive");
  if (walls_.empty()) return;
  Eigen::AlignedBox2d box;
  for (const WallSegment& wall : walls_) {
    check(wall.a.allFinite() && wall.b.allFinite(), "RayCaster: walls must be finite");
    box.extend(wall.a);
    box.extend(wall.b);
  }
  grid_min_ = box.min() - Eigen::Vector2d::Constant(2.0 * kBucketMargin);
  const Eigen::Vector2d size = box.max() - grid_min_ + Eigen::Vector2d::Constant(2.0 * kBucketMargin);
  const Eigen::Vector2d cells = (size / cell_size).array().ceil().max(1.0);
  check(cells.x() * cells.y() <= kMaxCells, "RayCaster: too many grid cells, use a larger cell size");
  nx_ = static_cast<int>(cells.x());
  ny_ = static_cast<int>(cells.y());
  buckets_.resize(static_cast<std::size_t>(nx_) * ny_);
  for (std::size_t i = 0; i < walls_.size(); ++i) {
    const Eigen::Vector2d low = walls_[i].a.cwiseMin(walls_[i].b).array() - kBucketMargin;
    const Eigen::Vector2d high = walls_[i].a.cwiseMax(walls_[i].b).array() + kBucketMargin;
    const int x0 = cell_index(low.x(), grid_min_.x(), cell_size, nx_);
    const int x1 = cell_index(high.x(), grid_min_.x(), cell_size, nx_);
    const int y0 = cell_index(low.y(), grid_min_.y(), cell_size, ny_);
    const int y1 = cell_index(high.y(), grid_min_.y(), cell_size, ny_);
    for (int iy = y0; iy <= y1; ++iy) {
      for (int ix = x0; ix <= x1; ++ix) buckets_[static_cast<std::size_t>(iy) * nx_ + ix].push_back(static_cast<int>(i));
    }
  }
}

std::optional<Eigen::Vector2d> RayCaster::clip_to_grid(const Eigen::Vector2d& origin, const Eigen::Vector2d& direction,
                                                       double max_range) const {
  double t_enter = 0.0;
  double t_leave = max_range;
  const Eigen::Vector2d grid_max = grid_min_ + cell_size_ * Eigen::Vector2d(nx_, ny_);
  for (int axis = 0; axis < 2; ++axis) {
    if (direction[axis] == 0.0) {
      if (origin[axis] < grid_min_[axis] || origin[axis] > grid_max[axis]) return std::nullopt;
      continue;
    }
    double t0 = (grid_min_[axis] - origin[axis]) / direction[axis];
    double t1 = (grid_max[axis] - origin[axis]) / direction[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_leave = std::min(t_leave, t1);
  }
  if (t_enter > t_leave) return std::nullopt;
  return Eigen::Vector2d(t_enter, t_leave);
}

std::optional<double> RayCaster::cast(const Eigen::Vector2d& origin, double angle, double max_range) const {
  if (walls_.empty() || !(max_range >= 0.0) || !origin.allFinite() || !std::isfinite(angle)) return std::nullopt;
  const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
  const auto span = clip_to_grid(origin, direction, max_range);
  if (!span) return std::nullopt;
  // The cell where the ray enters the grid, then one cell step at a time (Amanatides & Woo).
  const Eigen::Vector2d entry = origin + (*span)[0] * direction;
  int cell[2] = {cell_index(entry.x(), grid_min_.x(), cell_size_, nx_),
                 cell_index(entry.y(), grid_min_.y(), cell_size_, ny_)};
  const int limit[2] = {nx_, ny_};
  int step[2];
  double t_next[2];   // distance at which the ray crosses the next cell border along each axis
  double t_delta[2];  // distance between two borders along each axis
  for (int axis = 0; axis < 2; ++axis) {
    step[axis] = direction[axis] > 0.0 ? 1 : -1;
    if (direction[axis] == 0.0) {
      t_next[axis] = t_delta[axis] = kInfinity;
      continue;
    }
    const double border = grid_min_[axis] + cell_size_ * (cell[axis] + (step[axis] > 0 ? 1 : 0));
    t_next[axis] = (border - origin[axis]) / direction[axis];
    t_delta[axis] = cell_size_ / std::abs(direction[axis]);
  }
  double best = kInfinity;
  while (true) {
    for (const int index : bucket(cell[0], cell[1])) {
      const auto t = intersect_ray_segment(origin, direction, walls_[static_cast<std::size_t>(index)]);
      if (t && *t < best) best = *t;
    }
    const int axis = t_next[0] < t_next[1] ? 0 : 1;
    const double t_exit = t_next[axis];
    // Walls in later cells are met at t >= t_exit; a small tolerance covers rounding in t_next.
    if (best < t_exit - 1e-9 || t_exit > max_range) break;
    cell[axis] += step[axis];
    if (cell[axis] < 0 || cell[axis] >= limit[axis]) break;
    t_next[axis] += t_delta[axis];
  }
  if (best <= max_range) return best;
  return std::nullopt;
}

}  // namespace slam2d
