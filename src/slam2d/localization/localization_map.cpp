// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/localization_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr double kLogScale = 1000.0;  // the table holds round(1000 log p)
constexpr int kTileShift = 3;          // 8 x 8 samples per tile
constexpr int kTileMask = (1 << kTileShift) - 1;

// Index of sample (x, y) in the tiled table with `tiles_x` tiles per row.
inline std::size_t tiled_index(int x, int y, int tiles_x) {
  const std::size_t tile = static_cast<std::size_t>(y >> kTileShift) * static_cast<std::size_t>(tiles_x) +
                           static_cast<std::size_t>(x >> kTileShift);
  return tile << (2 * kTileShift) | static_cast<std::size_t>((y & kTileMask) << kTileShift | (x & kTileMask));
}

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
  // A point beyond the field is max_distance from every obstacle.
  const double far = field_.config().max_distance;
  const double sigma = field_.config().sigma_hit;
  outside_log_density_ = quantize_log(field_.config().z_hit / (std::sqrt(2.0 * std::numbers::pi) * sigma) *
                                          std::exp(-far * far / (2.0 * sigma * sigma)) +
                                      field_.config().z_rand / field_.config().z_max);
  // The table has a border of one sample on every side that holds the value beyond the field, so
  // a lookup clamps its coordinates instead of branching.
  tiles_x_ = (field_.width() + 2 + kTileMask) >> kTileShift;
  const int tiles_y = (field_.height() + 2 + kTileMask) >> kTileShift;
  log_density_.assign(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y) << (2 * kTileShift),
                      outside_log_density_);
  for (int y = 0; y < field_.height(); ++y) {
    for (int x = 0; x < field_.width(); ++x) {
      log_density_[tiled_index(x + 1, y + 1, tiles_x_)] = quantize_log(field_.beam_likelihood(field_.cell_center(x, y)));
    }
  }
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

LocalizationMap::FieldPose LocalizationMap::field_pose(const SE2& T_map_robot) const {
  // T_field_robot = T_field_map_ * T_map_robot, from the poses' cached cos / sin (no trig call),
  // scaled to samples and shifted by the border.
  const Eigen::Matrix2d R_field_map = T_field_map_.rotation();
  const Eigen::Matrix2d R = R_field_map * T_map_robot.rotation();
  const Eigen::Vector2d t = (R_field_map * T_map_robot.translation() + T_field_map_.translation()) * inverse_resolution_;
  return FieldPose{static_cast<float>(R(0, 0) * inverse_resolution_), static_cast<float>(R(1, 0) * inverse_resolution_),
                   static_cast<float>(t.x() + 1.0), static_cast<float>(t.y() + 1.0)};
}

// The table index of a robot-frame point at a pose. Single precision: four lanes per SSE
// instruction; a field of 10^4 samples a side is still resolved to 10^-3 of a sample. The
// coordinates are clamped onto the border: (int)(u + 1) is the sample of floor(u) for u in
// [0, width), the border for anything outside (NaN included).
inline std::uint32_t LocalizationMap::table_index(const FieldPose& pose, float px, float py) const {
  const float u_max = static_cast<float>(field_.width() + 1);
  const float v_max = static_cast<float>(field_.height() + 1);
  float u = pose.c * px - pose.s * py + pose.tx;
  float v = pose.s * px + pose.c * py + pose.ty;
  u = u > 0.0f ? u : 0.0f;
  v = v > 0.0f ? v : 0.0f;
  u = u < u_max ? u : u_max;
  v = v < v_max ? v : v_max;
  return static_cast<std::uint32_t>(tiled_index(static_cast<int>(u), static_cast<int>(v), tiles_x_));
}

double LocalizationMap::scan_log_likelihood(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot) const {
  const FieldPose pose = field_pose(T_map_robot);
  const std::int16_t* table = log_density_.data();
  // Two passes over chunks: the index computation has no branch; the table reads
  // (the cost) are then independent. Integer sums of quantised logs: no log call.
  constexpr std::size_t kChunk = 64;
  std::uint32_t index[kChunk];
  long sum = 0;
  const std::size_t n = points_robot.size();
  for (std::size_t begin = 0; begin < n; begin += kChunk) {
    const std::size_t count = std::min(kChunk, n - begin);
    for (std::size_t k = 0; k < count; ++k) {
      const Eigen::Vector2d& point = points_robot[begin + k];
      index[k] = table_index(pose, static_cast<float>(point.x()), static_cast<float>(point.y()));
    }
    for (std::size_t k = 0; k < count; ++k) sum += table[index[k]];
  }
  return static_cast<double>(sum) / kLogScale;
}

void LocalizationMap::scan_log_likelihoods(const std::vector<Eigen::Vector2d>& points_robot, const std::vector<SE2>& poses,
                                           std::vector<double>& log_likelihoods) const {
  log_likelihoods.resize(poses.size());
  const std::int16_t* table = log_density_.data();
  constexpr std::size_t kBlock = 256;
  FieldPose field_poses[kBlock];
  long sum[kBlock];
  std::uint32_t index[kBlock];
  for (std::size_t begin = 0; begin < poses.size(); begin += kBlock) {
    const std::size_t count = std::min(kBlock, poses.size() - begin);
    for (std::size_t k = 0; k < count; ++k) {
      field_poses[k] = field_pose(poses[begin + k]);
      sum[k] = 0;
    }
    for (const Eigen::Vector2d& point : points_robot) {
      const float px = static_cast<float>(point.x());
      const float py = static_cast<float>(point.y());
      for (std::size_t k = 0; k < count; ++k) index[k] = table_index(field_poses[k], px, py);
      for (std::size_t k = 0; k < count; ++k) sum[k] += table[index[k]];
    }
    for (std::size_t k = 0; k < count; ++k) log_likelihoods[begin + k] = static_cast<double>(sum[k]) / kLogScale;
  }
}

double LocalizationMap::plausibility(const std::vector<Eigen::Vector2d>& points_robot, const SE2& T_map_robot,
                                     double distance) const {
  if (points_robot.empty()) return 0.0;
  std::size_t near = 0;
  for (const Eigen::Vector2d& p : points_robot) near += field_.distance(T_map_robot.act(p)) <= distance ? 1 : 0;
  return static_cast<double>(near) / static_cast<double>(points_robot.size());
}

std::optional<MatchResult> LocalizationMap::match(const std::vector<Eigen::Vector2d>& points_robot, const SE2& guess,
                                                   const LikelihoodFieldMatchConfig& config) const {
  constexpr double kMinInlierFraction = 0.5;
  MatchResult result = match_likelihood_field(field_, points_robot, guess, config);
  if (result.inlier_fraction < kMinInlierFraction) return std::nullopt;
  return result;
}

std::size_t LocalizationMap::memory_bytes() const {
  return sizeof(*this) + map_.cells.capacity() + field_.memory_bytes() +
         free_cells_.capacity() * sizeof(Eigen::Vector2d) + log_density_.capacity() * sizeof(std::int16_t);
}

}  // namespace slam2d
