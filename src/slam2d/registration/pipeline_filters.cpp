// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/pipeline_filters.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {
namespace {

// Compacts the cloud in place to the points i with keep(i), in order (keep sees original indices).
template <typename Keep>
void keep_if(PointCloud2& cloud, Keep&& keep) {
  const bool normals = cloud.has_normals();
  const bool weights = cloud.has_weights();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!keep(i)) continue;
    cloud.points[kept] = cloud.points[i];
    if (normals) cloud.normals[kept] = cloud.normals[i];
    if (weights) cloud.weights[kept] = cloud.weights[i];
    ++kept;
  }
  cloud.points.resize(kept);
  if (normals) cloud.normals.resize(kept);
  if (weights) cloud.weights.resize(kept);
}

void apply(PointCloud2& cloud, const RangeClipFilter& filter) {
  const double min2 = filter.min * filter.min;
  const double max2 = filter.max * filter.max;
  keep_if(cloud, [&](std::size_t i) {
    const double r2 = cloud.points[i].squaredNorm();
    return r2 >= min2 && r2 <= max2;
  });
}

// The points of one voxel: sums for the centroid, mean normal and mean weight.
struct Voxel {
  std::size_t first = 0;  // index of its first point in the input
  Point2 point_sum = Point2::Zero();
  Point2 normal_sum = Point2::Zero();
  double weight_sum = 0.0;
  double count = 0.0;
};

std::vector<Voxel> collect_voxels(const PointCloud2& cloud, double size) {
  struct Keyed {
    double ix, iy;
    std::size_t index;
    auto operator<=>(const Keyed&) const = default;
  };
  std::vector<Keyed> keyed(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    keyed[i] = {std::floor(cloud.points[i].x() / size), std::floor(cloud.points[i].y() / size), i};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<Voxel> voxels;
  for (std::size_t k = 0; k < keyed.size(); ++k) {
    if (k == 0 || keyed[k].ix != keyed[k - 1].ix || keyed[k].iy != keyed[k - 1].iy) {
      voxels.push_back({.first = keyed[k].index});
    }
    Voxel& voxel = voxels.back();
    const std::size_t i = keyed[k].index;
    voxel.point_sum += cloud.points[i];
    if (cloud.has_normals()) voxel.normal_sum += cloud.normals[i];
    if (cloud.has_weights()) voxel.weight_sum += cloud.weights[i];
    voxel.count += 1.0;
  }
  std::sort(voxels.begin(), voxels.end(), [](const Voxel& a, const Voxel& b) { return a.first < b.first; });
  return voxels;
}

void apply(PointCloud2& cloud, const VoxelGridFilter& filter) {
  const std::vector<Voxel> voxels = collect_voxels(cloud, filter.size);
  PointCloud2 out;
  out.points.reserve(voxels.size());
  for (const Voxel& voxel : voxels) {
    out.points.push_back(voxel.point_sum / voxel.count);
    if (cloud.has_normals()) {
      const double norm = voxel.normal_sum.norm();
      out.normals.push_back(norm > 1e-9 ? Point2(voxel.normal_sum / norm) : Point2::Zero());
    }
    if (cloud.has_weights()) out.weights.push_back(voxel.weight_sum / voxel.count);
  }
  cloud = std::move(out);
}

void apply(PointCloud2& cloud, const RandomSubsampleFilter& filter) {
  const std::size_t n = cloud.size();
  if (n == 0) return;
  const auto wanted = static_cast<std::size_t>(std::llround(filter.ratio * static_cast<double>(n)));
  const std::size_t keep = std::clamp<std::size_t>(wanted, 1, n);
  Rng rng(filter.seed);
  std::size_t selected = 0;
  // Algorithm S: point i is selected with probability (still needed) / (still available).
  keep_if(cloud, [&](std::size_t i) {
    const bool take = rng.uniform() * static_cast<double>(n - i) < static_cast<double>(keep - selected);
    if (take) ++selected;
    return take;
  });
}

void apply(PointCloud2& cloud, const NormalsFilter& filter) {
  if (cloud.empty()) {
    cloud.normals.clear();
    return;
  }
  const NormalEstimationConfig config{.neighbors = filter.neighbors,
                                      .max_neighbor_distance = filter.max_neighbor_distance,
                                      .min_neighbors = filter.min_neighbors};
  if (filter.ordered) {
    estimate_normals_ordered(cloud, config);
  } else {
    estimate_normals(cloud, config);
  }
}

void reject(const MaxDistanceFilter& filter, const PairContext& /*context*/, std::vector<PointPair>& pairs,
            std::vector<double>& /*scratch*/) {
  const double max2 = filter.distance * filter.distance;
  std::erase_if(pairs, [&](const PointPair& pair) { return pair.squared_distance > max2; });
}

void reject(const TrimmedFilter& filter, const PairContext& /*context*/, std::vector<PointPair>& pairs,
            std::vector<double>& scratch) {
  const std::size_t n = pairs.size();
  if (n == 0) return;
  const auto wanted = static_cast<std::size_t>(std::llround(filter.ratio * static_cast<double>(n)));
  keep_closest_pairs(pairs, std::clamp<std::size_t>(wanted, 1, n), scratch);  // trimmed ICP's own
}

void reject(const MedianFactorFilter& filter, const PairContext& /*context*/, std::vector<PointPair>& pairs,
            std::vector<double>& scratch) {
  const std::size_t n = pairs.size();
  if (n == 0) return;
  // The ceil(q n)-th smallest (the 1e-9 absorbs q n = 7.000000000000001 for q = 0.7, n = 10).
  const double rank = std::ceil(filter.quantile * static_cast<double>(n) - 1e-9);
  const std::size_t k = std::clamp<std::size_t>(static_cast<std::size_t>(std::max(rank, 1.0)), 1, n);
  scratch.resize(n);
  for (std::size_t i = 0; i < n; ++i) scratch[i] = pairs[i].squared_distance;
  std::nth_element(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(k - 1), scratch.end());
  const double max2 = filter.factor * filter.factor * scratch[k - 1];  // squared distances: factor^2
  std::erase_if(pairs, [&](const PointPair& pair) { return pair.squared_distance > max2; });
}

void reject(const NormalAngleFilter& filter, const PairContext& context, std::vector<PointPair>& pairs,
            std::vector<double>& /*scratch*/) {
  const double min_cos = std::cos(filter.max_angle);
  const Eigen::Matrix2d R = context.T_target_source.rotation();
  std::erase_if(pairs, [&](const PointPair& pair) {
    if (!has_normal(context.source, pair.source) || !has_normal(context.target, pair.target)) return true;
    return (R * context.source.normals[pair.source]).dot(context.target.normals[pair.target]) < min_cos;
  });
}

}  // namespace

void validate(const DataFilterConfig& filter) {
  std::visit(
      [](const auto& f) {
        check_fields(f, "pipeline: " + std::string(f.kind) + " filter");
        if constexpr (std::is_same_v<std::decay_t<decltype(f)>, RangeClipFilter>) {
          check(f.max > f.min, "pipeline: range_clip filter: max must be > min");
        }
      },
      filter);
}

void validate(const OutlierFilterConfig& filter) {
  std::visit([](const auto& f) { check_fields(f, "pipeline: " + std::string(f.kind) + " filter"); }, filter);
}

void apply_data_filter(PointCloud2& cloud, const DataFilterConfig& filter) {
  validate(filter);
  std::visit([&](const auto& f) { apply(cloud, f); }, filter);
}

void apply_data_filters(PointCloud2& cloud, const std::vector<DataFilterConfig>& filters) {
  for (const DataFilterConfig& filter : filters) apply_data_filter(cloud, filter);
}

void apply_outlier_filter(const OutlierFilterConfig& filter, const PairContext& context, std::vector<PointPair>& pairs,
                          std::vector<double>& scratch) {
  std::visit([&](const auto& f) { reject(f, context, pairs, scratch); }, filter);
}

void apply_outlier_filters(const std::vector<OutlierFilterConfig>& filters, const PairContext& context,
                           std::vector<PointPair>& pairs, std::vector<double>& scratch) {
  for (const OutlierFilterConfig& filter : filters) apply_outlier_filter(filter, context, pairs, scratch);
}

}  // namespace slam2d
