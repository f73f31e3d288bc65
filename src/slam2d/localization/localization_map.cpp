#include "slam2d/localization/localization_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr double kLogScale = 1000.0;  // the table holds round(1000 log p)

std::int16_t quantize_log(double density) {
  return static_cast<std::int16_t>(std::clamp(std::lround(kLogScale * std::log(density)), -32000L, 32000L));
}

}  // namespace

LocalizationMap::LocalizationMap(OccupancyMap map, const LikelihoodFieldConfig& field_config)
    : map_(std::move(map)), field_(map_, field_config) {
  check(map_.width > 0 && map_.height > 0, "localization: the map is empty");
  for (int iy = 0; iy < map_.height; ++iy) {
    for (int ix = 0; ix < map_.width; ++ix) {
      const std::int8_t cell = map_.at(ix, iy);
      if (cell >= 0 && cell < 50) free_cells_.push_back(map_.cell_center(ix, iy));
    }
  }
  check(!free_cells_.empty(), "localization: the map has no free cells");
  T_field_map_ = field_.origin().inverse();
  inverse_resolution_ = 1.0 / field_.resolution();
  log_density_.resize(static_cast<std::size_t>(field_.width()) * field_.height());
  for (int y = 0; y < field_.height(); ++y) {
    for (int x = 0; x < field_.width(); ++x) {
      log_density_[static_cast<std::size_t>(y) * field_.width() + x] = quantize_log(field_.beam_likelihood(field_.cell_center(x, y)));
    }
  }
  // A point beyond the field is max_distance from every obstacle.
  const double far = field_.config().max_distance;
  const double sigma = field_.config().sigma_hit;
  outside_log_density_ = quantize_log(field_.config().z_hit / (std::sqrt(2.0 * std::numbers::pi) * sigma) *
                                          std::exp(-far * far / (2.0 * sigma * sigma)) +
                                      field_.config().z_rand / field_.config().z_max);
}

bool LocalizationMap::is_free(const Eigen::Vector2d& point_map) const {
  const Eigen::Vector2i cell = map_.cell_of(point_map);
  if (!map_.contains(cell.x(), cell.y())) return false;
  const std::int8_t value = map_.at(cell.x(), cell.y());
  return value >= 0 && value < 50;
}

SE2 LocalizationMap::sample_free_pose(Rng& rng) const {
  const Eigen::Vector2d& centre = free_cells_[rng.uniform_index(free_cells_.size())];
  const double half = 0.5 * map_.resolution;
  // The map may be rotated: offsets along its axes.
  const Eigen::Vector2d offset = map_.origin.rotation() * Eigen::Vector2d(rng.uniform(-half, half), rng.uniform(-half, half));
  return SE2(centre + offset, rng.uniform(-std::numbers::pi, std::numbers::pi));
}

double LocalizationMap::scan_log_likelihood(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot) const {
  // T_field_robot = T_field_map_ * T_map_robot, from the poses' cached cos / sin (no trig call).
  const Eigen::Matrix2d R_field_map = T_field_map_.rotation();
  const Eigen::Matrix2d R = R_field_map * T_map_robot.rotation();
  const Eigen::Vector2d t = (R_field_map * T_map_robot.translation() + T_field_map_.translation()) * inverse_resolution_;
  const double c = R(0, 0) * inverse_resolution_;
  const double s = R(1, 0) * inverse_resolution_;
  const double tx = t.x();
  const double ty = t.y();
  const int width = field_.width();
  const int height = field_.height();
  const std::int16_t* table = log_density_.data();
  // Integer sums of quantised logs: no multiply chain, no log call, a quarter of the memory of
  // a double table (the reads are what costs).
  long sum = 0;
  for (const Eigen::Vector2d& p : points_robot) {
    // Field cell coordinates; cell (i, j) covers [i, i + 1) x [j, j + 1).
    const double u = c * p.x() - s * p.y() + tx;
    const double v = s * p.x() + c * p.y() + ty;
    if (u >= 0.0 && v >= 0.0 && u < width && v < height) {
      sum += table[static_cast<std::size_t>(static_cast<int>(v)) * width + static_cast<int>(u)];
    } else {
      sum += outside_log_density_;
    }
  }
  return static_cast<double>(sum) / kLogScale;
}

double LocalizationMap::plausibility(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot,
                                     double distance) const {
  if (points_robot.empty()) return 0.0;
  std::size_t near = 0;
  for (const Eigen::Vector2d& p : points_robot) near += field_.distance(T_map_robot.act(p)) <= distance ? 1 : 0;
  return static_cast<double>(near) / static_cast<double>(points_robot.size());
}

std::size_t LocalizationMap::memory_bytes() const {
  return sizeof(*this) + map_.cells.capacity() + field_.memory_bytes() +
         free_cells_.capacity() * sizeof(Eigen::Vector2d) + log_density_.capacity() * sizeof(std::int16_t);
}

}  // namespace slam2d
