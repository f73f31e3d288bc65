// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/fusion/trajectory_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <optional>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

// A segment whose dense end points are closer than this (m), or whose similarity would scale
// the dense path by more than kMaxScaleChange, is not a similarity: the robot (nearly) stood, and
// the dense path's noise would be magnified. It is blended instead (see the header).
constexpr double kMinSpan = 0.05;
constexpr double kMaxScaleChange = 0.5;
// A segment along which the dense path travels less than this (m) has no usable progress: its
// corrections are interpolated in time instead (the robot turned in place or stood).
constexpr double kMinProgress = 0.001;

/// A sparse pose and the dense pose at its stamp.
struct Anchor {
  double stamp = 0.0;
  SE2 sparse;
  SE2 dense;
  double progress = 0.0;  // distance the dense path has travelled at this stamp (m)
  double heading_correction() const { return normalize_angle(sparse.theta() - dense.theta()); }
};

/// The map of dense positions onto fused ones over one segment: z -> a z + b in complex numbers.
struct Similarity {
  std::complex<double> a{1.0, 0.0};
  std::complex<double> b{0.0, 0.0};
  Eigen::Vector2d operator()(const Eigen::Vector2d& p) const {
    const std::complex<double> z = a * std::complex<double>(p.x(), p.y()) + b;
    return {z.real(), z.imag()};
  }
};

std::complex<double> complex_of(const SE2& pose) { return {pose.x(), pose.y()}; }

/// The rigid motion taking anchor's dense pose onto its sparse one, as a similarity of scale 1.
Similarity rigid(const Anchor& anchor) {
  const SE2 T = anchor.sparse * anchor.dense.inverse();
  return {std::polar(1.0, T.theta()), complex_of(T)};
}

/// The similarity of a segment, or nullopt where the segment is to be blended.
std::optional<Similarity> segment_similarity(const Anchor& first, const Anchor& last) {
  const std::complex<double> dense_span = complex_of(last.dense) - complex_of(first.dense);
  if (std::abs(dense_span) < kMinSpan) return std::nullopt;
  const std::complex<double> a = (complex_of(last.sparse) - complex_of(first.sparse)) / dense_span;
  if (std::abs(std::abs(a) - 1.0) > kMaxScaleChange) return std::nullopt;
  return Similarity{a, complex_of(first.sparse) - a * complex_of(first.dense)};
}

/// A blended segment's position at fraction s: the two end anchors' rigid motions, weighted.
Eigen::Vector2d blend(const Anchor& first, const Anchor& last, double s, const Eigen::Vector2d& dense) {
  return (1.0 - s) * rigid(first)(dense) + s * rigid(last)(dense);
}

SE2 apply(const Similarity& map, const SE2& dense, double heading_correction) {
  return SE2(map(dense.translation()), normalize_angle(dense.theta() + heading_correction));
}

/// The anchors' corrections C_k = S_k * D_k^-1 averaged with Gaussian weights in time, and each
/// anchor's sparse pose replaced by C'_k * D_k (see the header).
void smooth_corrections(std::vector<Anchor>& anchors, double sigma) {
  if (sigma <= 0.0 || anchors.size() < 2) return;
  std::vector<Eigen::Vector3d> corrections(anchors.size());
  double previous_theta = 0.0;
  for (std::size_t k = 0; k < anchors.size(); ++k) {
    const SE2 C = anchors[k].sparse * anchors[k].dense.inverse();
    const double theta = k == 0 ? C.theta() : previous_theta + normalize_angle(C.theta() - previous_theta);
    corrections[k] = {C.x(), C.y(), theta};
    previous_theta = theta;
  }
  std::vector<SE2> smoothed(anchors.size());
  const double reach = 4.0 * sigma;
  std::size_t low = 0;
  std::size_t high = 0;
  for (std::size_t k = 0; k < anchors.size(); ++k) {
    while (anchors[low].stamp < anchors[k].stamp - reach) ++low;
    while (high + 1 < anchors.size() && anchors[high + 1].stamp <= anchors[k].stamp + reach) ++high;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weights = 0.0;
    for (std::size_t j = low; j <= high; ++j) {
      const double u = (anchors[j].stamp - anchors[k].stamp) / sigma;
      const double w = std::exp(-0.5 * u * u);
      sum += w * corrections[j];
      weights += w;
    }
    const Eigen::Vector3d mean = sum / weights;
    smoothed[k] = SE2(mean.x(), mean.y(), normalize_angle(mean.z())) * anchors[k].dense;
  }
  for (std::size_t k = 0; k < anchors.size(); ++k) anchors[k].sparse = smoothed[k];
}

/// The distance travelled along the (sorted) dense trajectory up to each of its poses.
std::vector<double> travelled(const Trajectory& dense) {
  std::vector<double> distance(dense.size(), 0.0);
  for (std::size_t i = 1; i < dense.size(); ++i) {
    distance[i] = distance[i - 1] + (dense[i].pose.translation() - dense[i - 1].pose.translation()).norm();
  }
  return distance;
}

/// The distance travelled at `stamp` (within the dense span), interpolated between the poses around it.
double travelled_at(const Trajectory& dense, const std::vector<double>& distance, double stamp) {
  const auto after = std::lower_bound(dense.begin(), dense.end(), stamp,
                                      [](const StampedPose& pose, double t) { return pose.stamp < t; });
  const auto i = static_cast<std::size_t>(after - dense.begin());
  if (i == 0) return distance.front();
  if (i == dense.size()) return distance.back();
  const double span = dense[i].stamp - dense[i - 1].stamp;
  const double s = span > 0.0 ? (stamp - dense[i - 1].stamp) / span : 1.0;
  return distance[i - 1] + s * (distance[i] - distance[i - 1]);
}

/// Where a dense pose lies between a segment's two anchors, 0 at the first and 1 at the last: by
/// distance travelled, so that a correction changes only while the robot moves (a standing Hector
/// does not drift, and its relative motion is kept exactly), by time where the segment has no progress.
double segment_fraction(const Anchor& first, const Anchor& last, double stamp, double progress) {
  const double span = last.progress - first.progress;
  if (span >= kMinProgress) return std::clamp((progress - first.progress) / span, 0.0, 1.0);
  return (stamp - first.stamp) / (last.stamp - first.stamp);
}

}  // namespace

void validate(const FusionConfig& config) { check_fields(config, "FusionConfig"); }

Trajectory fuse_trajectories(const Trajectory& dense_in, const Trajectory& sparse_in, const FusionConfig& config,
                             FusionStats* stats) {
  validate(config);
  check(!dense_in.empty(), "fuse: the dense trajectory is empty");
  check(!sparse_in.empty(), "fuse: the sparse trajectory is empty");
  const Trajectory dense = dense_in.sorted_by_stamp();
  const Trajectory sparse = sparse_in.sorted_by_stamp();
  const std::vector<double> distance = travelled(dense);
  std::vector<Anchor> anchors;
  for (const StampedPose& pose : sparse) {
    const std::optional<SE2> at = dense.interpolate(pose.stamp);
    if (at && (anchors.empty() || pose.stamp > anchors.back().stamp)) {
      anchors.push_back({pose.stamp, pose.pose, *at, travelled_at(dense, distance, pose.stamp)});
    }
  }
  check(!anchors.empty(), "fuse: no sparse pose falls within the dense trajectory's time span");
  smooth_corrections(anchors, config.correction_smoothing);

  FusionStats local;
  local.sparse_used = anchors.size();
  std::vector<std::optional<Similarity>> maps(anchors.size() > 1 ? anchors.size() - 1 : 0);
  for (std::size_t k = 0; k + 1 < anchors.size(); ++k) {
    if (config.alignment == FusionAlignment::kSimilarity) maps[k] = segment_similarity(anchors[k], anchors[k + 1]);
    if (!maps[k]) ++local.blended_segments;
    if (maps[k]) local.max_scale_change = std::max(local.max_scale_change, std::abs(std::abs(maps[k]->a) - 1.0));
  }
  local.segments = maps.size();

  Trajectory fused;
  fused.reserve(dense.size());
  std::size_t k = 0;  // the segment [anchors[k], anchors[k + 1]] holding the current stamp
  for (std::size_t i = 0; i < dense.size(); ++i) {
    const StampedPose& pose = dense[i];
    const double t = pose.stamp;
    if (t <= anchors.front().stamp) {
      fused.push_back(t, apply(rigid(anchors.front()), pose.pose, anchors.front().heading_correction()));
    } else if (t >= anchors.back().stamp) {
      fused.push_back(t, apply(rigid(anchors.back()), pose.pose, anchors.back().heading_correction()));
    } else {
      while (anchors[k + 1].stamp < t) ++k;
      const Anchor& first = anchors[k];
      const Anchor& last = anchors[k + 1];
      const double s = segment_fraction(first, last, t, distance[i]);
      const double correction = first.heading_correction() +
                                s * normalize_angle(last.heading_correction() - first.heading_correction());
      fused.push_back(t, maps[k] ? apply(*maps[k], pose.pose, correction)
                                 : SE2(blend(first, last, s, pose.pose.translation()),
                                       normalize_angle(pose.pose.theta() + correction)));
    }
  }
  if (stats != nullptr) *stats = local;
  return fused;
}

}  // namespace slam2d
