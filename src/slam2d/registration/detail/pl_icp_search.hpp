// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Eq. (2) of PL-ICP (A. Censi, "An ICP variant using a point-to-line metric", ICRA 2008): the
// closest target point j1 of a moved source point, by the projective search over the ordered
// target scan (CSM's "correspondence tricks") or by kd-tree. Internal to the registration module:
// pl_icp.cpp, and the projective association of the modular pipeline (pipeline_stages.cpp) --
// the one projective point search of the library; pl_icp_test checks it against brute force.
//
// The projective search walks the ordered target up and down from the previous iteration's
// match (or from the query's bearing), skipping runs of points with the jump tables (the next
// point farther / nearer from the sensor on either side) and stopping each side with the bound
// |p| sin(delta bearing). It is exact: it finds the same j1 as the kd-tree. Bearings are
// compared as pseudo-angles (monotone in the bearing, a half turn = 2), one division each.
//
// Every search also yields a clearance: a lower bound on the distance from the query to every
// target point other than j1 (to every point when there is none within reach); the kd-tree's is
// the distance of the second-closest point (of the closest, when it is out of reach). Once the
// estimate moves by little, a source point whose drift d from where it was last searched
// satisfies |p - p_j1| < clearance - d keeps j1 without any walk: every other point is at least
// clearance - d away (triangle inequality). TrackedNearest carries that certificate from one
// iteration to the next.

#include <limits>
#include <memory>
#include <vector>

#include "slam2d/core/point_cloud.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/pl_icp.hpp"

namespace slam2d::pl_icp_detail {

constexpr int kNone = -1;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kMinRange = 1e-3;  // m: target points this close to the sensor have no bearing

/// The target, prepared once per match: its usable points in scan order with their ranges, unit
/// bearing vectors and unwrapped bearings; the jump tables of the projective search are built on
/// the first walk that needs them (most walks end within a few steps).
struct TargetIndex {
  std::vector<std::size_t> original;    // cloud index of each usable point
  std::vector<Point2> points;           // m
  std::vector<Point2> directions;       // unit bearing vectors
  std::vector<double> ranges;           // m
  std::vector<double> bearings;         // pseudo-angles, unwrapped, strictly increasing when `ordered`
  std::vector<Point2> segment_normals;  // unit normal of the segment (k, k + 1)
  std::vector<double> segment_lengths;  // m, |p_{k+1} - p_k|
  mutable std::vector<int> up_bigger, up_smaller, down_bigger, down_smaller;  // when jump_tables_built
  mutable bool jump_tables_built = false;
  bool ordered = false;                 // bearings increase over less than a full turn
  double gap_center = 0.0;              // pseudo-angle, the middle of the unscanned sector
  std::unique_ptr<KdTree2> tree;        // kd-tree search (config, or an unordered target)

  int size() const { return static_cast<int>(points.size()); }
};

/// The usable target points (range >= kMinRange, finite) and the index `search` asks for; an
/// unordered target gets the kd-tree whatever `search` says.
/// Do not move the result once it holds a kd-tree: the tree indexes the `points` member in
/// place (build a long-lived index with the overload below, into an object that stays put).
TargetIndex prepare_target(const PointCloud2& target, PlIcpSearch search);
/// The same into `t`, reusing its buffers (no allocation once they are large enough).
void prepare_target(const PointCloud2& target, PlIcpSearch search, TargetIndex& t);

/// A source point's closest target point across iterations, with its certificate.
struct TrackedNearest {
  Point2 anchor = Point2::Zero();  // m, where the last full search ran
  double clearance = 0.0;          // m, every target point but `index` was at least this far from anchor
  int index = kNone;               // j1 at the last query, kNone: none within reach
};

/// The search behind track_nearest: renews `tracked` at p.
int search_and_track(const TargetIndex& t, const Point2& p, double max_distance, TrackedNearest& tracked,
                     int start);

/// The closest target point strictly within max_distance of p (kNone if none): reuses the
/// certificate in `tracked` when it still holds, else searches and renews it. The projective
/// walk starts at the previous j1, else at `start` (e.g. the neighbouring source point's j1;
/// kNone: at p's bearing). Exact either way. Inline: it runs for every source point and
/// iteration, and mostly ends at the certificate.
inline int track_nearest(const TargetIndex& t, const Point2& p, double max_distance, TrackedNearest& tracked,
                         int start = kNone) {
  constexpr double kSlack = 1e-9;  // m: the certificate must hold by this much (rounding)
  if (tracked.clearance > 0.0) {
    // Every point but tracked.index is at least `margin` from p.
    const double margin = tracked.clearance - (p - tracked.anchor).norm() - kSlack;
    if (margin > 0.0) {
      if (tracked.index == kNone) {
        if (margin >= max_distance) return kNone;
      } else {
        const double d2 = (p - t.points[tracked.index]).squaredNorm();
        if (d2 < margin * margin) return d2 < max_distance * max_distance ? tracked.index : kNone;
      }
    }
  }
  return search_and_track(t, p, max_distance, tracked, start);
}

}  // namespace slam2d::pl_icp_detail
