// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/fusion/trajectory_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

constexpr double kCoincident = 1e-6;  // m: dense end points closer than this give no scale or rotation

/// A sparse pose and the dense pose at its stamp.
struct Anchor {
  double stamp = 0.0;
  SE2 sparse;
  SE2 dense;
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

Similarity segment_similarity(const Anchor& first, const Anchor& last, bool& is_rigid) {
  const std::complex<double> dense_span = complex_of(last.dense) - complex_of(first.dense);
  is_rigid = std::abs(dense_span) < kCoincident;
  if (is_rigid) return rigid(first);
  const std::complex<double> a = (complex_of(last.sparse) - complex_of(first.sparse)) / dense_span;
  return {a, complex_of(first.sparse) - a * complex_of(first.dense)};
}

SE2 apply(const Similarity& map, const SE2& dense, double heading_correction) {
  return SE2(map(dense.translation()), normalize_angle(dense.theta() + heading_correction));
}

}  // namespace

Trajectory fuse_trajectories(const Trajectory& dense_in, const Trajectory& sparse_in, FusionStats* stats) {
  check(!dense_in.empty(), "fuse: the dense trajectory is empty");
  check(!sparse_in.empty(), "fuse: the sparse trajectory is empty");
  const Trajectory dense = dense_in.sorted_by_stamp();
  const Trajectory sparse = sparse_in.sorted_by_stamp();
  std::vector<Anchor> anchors;
  for (const StampedPose& pose : sparse) {
    const std::optional<SE2> at = dense.interpolate(pose.stamp);
    if (at && (anchors.empty() || pose.stamp > anchors.back().stamp)) anchors.push_back({pose.stamp, pose.pose, *at});
  }
  check(!anchors.empty(), "fuse: no sparse pose falls within the dense trajectory's time span");

  FusionStats local;
  local.sparse_used = anchors.size();
  std::vector<Similarity> maps(anchors.size() > 1 ? anchors.size() - 1 : 0);
  for (std::size_t k = 0; k + 1 < anchors.size(); ++k) {
    bool is_rigid = false;
    maps[k] = segment_similarity(anchors[k], anchors[k + 1], is_rigid);
    local.rigid_segments += is_rigid ? 1 : 0;
    local.max_scale_change = std::max(local.max_scale_change, std::abs(std::abs(maps[k].a) - 1.0));
  }
  local.segments = maps.size();

  Trajectory fused;
  fused.reserve(dense.size());
  std::size_t k = 0;  // the segment [anchors[k], anchors[k + 1]] holding the current stamp
  for (const StampedPose& pose : dense) {
    const double t = pose.stamp;
    if (t <= anchors.front().stamp) {
      fused.push_back(t, apply(rigid(anchors.front()), pose.pose, anchors.front().heading_correction()));
    } else if (t >= anchors.back().stamp) {
      fused.push_back(t, apply(rigid(anchors.back()), pose.pose, anchors.back().heading_correction()));
    } else {
      while (anchors[k + 1].stamp < t) ++k;
      const Anchor& first = anchors[k];
      const Anchor& last = anchors[k + 1];
      const double s = (t - first.stamp) / (last.stamp - first.stamp);
      const double correction = first.heading_correction() +
                                s * normalize_angle(last.heading_correction() - first.heading_correction());
      fused.push_back(t, apply(maps[k], pose.pose, correction));
    }
  }
  if (stats != nullptr) *stats = local;
  return fused;
}

}  // namespace slam2d
