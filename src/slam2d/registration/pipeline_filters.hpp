// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The filters of the modular ICP pipeline (pipeline.hpp), after libpointmatcher's data-points
// filters and outlier filters: F. Pomerleau, F. Colas, R. Siegwart, S. Magnenat, "Comparing ICP
// variants on real-world data sets", Autonomous Robots 34(3), 2013, Sec. 3 (Fig. 1: reading and
// reference filters, matching, outlier rejection, error minimisation, transformation checks), and
// their review "A review of point cloud registration algorithms for mobile robotics",
// Foundations and Trends in Robotics 4(1), 2015, Sec. 4.1 (filtering) and 4.3 (rejection).
//
// A data filter runs once per match on a cloud in its sensor frame; an outlier filter runs at
// every iteration on the current pairs. Each filter is a small struct of its parameters; a list
// of them is a std::vector of std::variant, visited once per filter and call, never per point.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string_view>
#include <variant>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/point_cloud.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/registration/nearest_association.hpp"  // PointPair, the pairs of every closest-point matcher

namespace slam2d {

// ---------------------------------------------------------------------------------------------
// Data filters (once per match).

/// Keeps the points whose distance from the sensor (the cloud's origin) lies in [min, max].
struct RangeClipFilter {
  static constexpr std::string_view kind = "range_clip";  // in a YAML filter list
  double min = 0.0;
  double max = std::numeric_limits<double>::infinity();

  bool operator==(const RangeClipFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, RangeClipFilter& c) {
  f.number("min", c.min, "m", at_least(0), "points nearer the sensor are dropped");
  f.number("max", c.max, "m", or_infinity(greater_than(0)), "points at or beyond are dropped (> min)");
}

/// Replaces the points of each occupied cell of a square grid aligned with the origin (cell
/// [i size, (i+1) size) x [j size, (j+1) size)) by their centroid; normals (if any) by their
/// normalised mean, weights (if any) by their mean. The cells come out in the order of their
/// first point, so a scan stays in beam order.
struct VoxelGridFilter {
  static constexpr std::string_view kind = "voxel";  // in a YAML filter list
  double size = 0.05;

  bool operator==(const VoxelGridFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, VoxelGridFilter& c) {
  f.number("size", c.size, "m", greater_than(0), "cell side");
}

/// Keeps exactly max(1, round(ratio n)) of the n points, each subset of that size equally likely
/// (selection sampling, D. Knuth, TAOCP Vol. 2, Algorithm 3.4.2 S), in their original order.
/// The same seed gives the same subset.
struct RandomSubsampleFilter {
  static constexpr std::string_view kind = "random";  // in a YAML filter list
  double ratio = 0.5;
  std::uint64_t seed = 1;

  bool operator==(const RandomSubsampleFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, RandomSubsampleFilter& c) {
  f.number("ratio", c.ratio, "1", open_closed(0, 1), "fraction kept");
  f.number("seed", c.seed, "1", any_value(), "of slam2d::Rng");
}

/// Sets the cloud's normals (the tangent's perpendicular, facing the sensor) by a line fit to
/// the neighbours (normals.hpp): the k nearest (kd-tree) or, when `ordered`, the neighbours in
/// scan order. Points with too few neighbours get no normal.
struct NormalsFilter {
  static constexpr std::string_view kind = "normals";  // in a YAML filter list
  int neighbors = 5;
  double max_neighbor_distance = 0.5;
  int min_neighbors = 3;
  bool ordered = false;

  bool operator==(const NormalsFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, NormalsFilter& c) {
  f.number("neighbors", c.neighbors, "1", at_least(2), "points in the fit (itself included)");
  f.number("max_neighbor_distance", c.max_neighbor_distance, "m", greater_than(0), "farther neighbours are left out");
  f.number("min_neighbors", c.min_neighbors, "1", at_least(2), "fewer points in the fit give no normal");
  f.flag("ordered", c.ordered, "neighbours in scan order (the cloud must be in beam order)");
}

using DataFilterConfig = std::variant<RangeClipFilter, VoxelGridFilter, RandomSubsampleFilter, NormalsFilter>;

/// The filter's `kind` in a YAML file: range_clip, voxel, random, normals.
inline std::string_view kind_name(const DataFilterConfig& filter) {
  return std::visit([](const auto& f) { return f.kind; }, filter);
}
/// Throws Error naming the filter and the parameter when a value is out of range.
void validate(const DataFilterConfig& filter);
/// Applies one filter (validated) to the cloud in place.
void apply_data_filter(PointCloud2& cloud, const DataFilterConfig& filter);
/// Applies the filters in order.
void apply_data_filters(PointCloud2& cloud, const std::vector<DataFilterConfig>& filters);

// ---------------------------------------------------------------------------------------------
// Outlier filters (every iteration, in order, on the pairs left by the previous one; a PointPair
// is source point `source`, moved by the current estimate T, against target point `target`).

/// Rejects the pairs farther apart than `distance`.
struct MaxDistanceFilter {
  static constexpr std::string_view kind = "max_distance";  // in a YAML filter list
  double distance = 0.5;

  bool operator==(const MaxDistanceFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, MaxDistanceFilter& c) {
  f.number("distance", c.distance, "m", greater_than(0), "pairs farther apart are rejected");
}

/// Keeps the max(1, round(ratio n)) closest of the n pairs (least trimmed squares, D. Chetverikov et al.,
/// "The trimmed iterative closest point algorithm", ICPR 2002); ties at the cut are kept in order.
struct TrimmedFilter {
  static constexpr std::string_view kind = "trimmed";  // in a YAML filter list
  double ratio = 0.9;

  bool operator==(const TrimmedFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, TrimmedFilter& c) {
  f.number("ratio", c.ratio, "1", open_closed(0, 1), "fraction of the pairs kept");
}

/// Rejects the pairs farther apart than factor x the `quantile` of the pair distances: the
/// median factor filter of libpointmatcher with quantile 0.5, Censi's adaptive outlier rejection
/// (CSM's outliers_adaptive_order 0.7, outliers_adaptive_mult 2) with quantile 0.7. The
/// q-quantile of n distances is the ceil(q n)-th smallest (for an even count the lower median).
struct MedianFactorFilter {
  static constexpr std::string_view kind = "median_factor";  // in a YAML filter list
  double factor = 3.0;
  double quantile = 0.5;

  bool operator==(const MedianFactorFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, MedianFactorFilter& c) {
  f.number("factor", c.factor, "1", at_least(1), "pairs farther than factor x the quantile are rejected");
  f.number("quantile", c.quantile, "1", open_closed(0, 1), "0.5: the median");
}

/// Rejects the pairs whose normals (the source's rotated by T) differ by more than `max_angle`,
/// and the pairs where either point has no normal.
struct NormalAngleFilter {
  static constexpr std::string_view kind = "normal_angle";  // in a YAML filter list
  double max_angle = std::numbers::pi / 4.0;

  bool operator==(const NormalAngleFilter&) const = default;
};
template <typename Fields>
void describe(Fields& f, NormalAngleFilter& c) {
  f.number("max_angle", c.max_angle, "rad", between(0, std::numbers::pi), "pairs whose normals differ more are rejected");
}

using OutlierFilterConfig = std::variant<MaxDistanceFilter, TrimmedFilter, MedianFactorFilter, NormalAngleFilter>;

/// The filter's `kind` in a YAML file: max_distance, trimmed, median_factor, normal_angle.
inline std::string_view kind_name(const OutlierFilterConfig& filter) {
  return std::visit([](const auto& f) { return f.kind; }, filter);
}
void validate(const OutlierFilterConfig& filter);

/// What an outlier filter may look at besides the pairs.
struct PairContext {
  const PointCloud2& target;
  const PointCloud2& source;
  const SE2& T_target_source;  // the current estimate
};

/// Removes the pairs the filter rejects, keeping the others in order. The filter must be valid
/// (validate(); match_pipeline checks once per match, not per iteration). `scratch` is a buffer
/// the caller reuses across calls (no allocation once it has grown).
void apply_outlier_filter(const OutlierFilterConfig& filter, const PairContext& context, std::vector<PointPair>& pairs,
                          std::vector<double>& scratch);
/// Applies the filters in order.
void apply_outlier_filters(const std::vector<OutlierFilterConfig>& filters, const PairContext& context,
                           std::vector<PointPair>& pairs, std::vector<double>& scratch);

}  // namespace slam2d
