// SPDX-License-Identifier: BSD-3-Clause
// Eq. (2) of PL-ICP (Censi 2008): the projective search with jump tables and its clearance
// certificate (pl_icp_search.hpp), and the kd-tree fallback.

#include "slam2d/registration/detail/pl_icp_search.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace slam2d::pl_icp_detail {
namespace {

// The search compares bearings as pseudo-angles (pseudo_bearing below): a half turn is 2.
constexpr double kHalfTurn = 2.0;
constexpr double kFullTurn = 4.0;

// ---------------------------------------------------------------------------------------------
// A pseudo-angle of (x, y) in (-2, 2] ("diamond angle"): strictly increasing with the bearing
// atan2(y, x) on (-pi, pi], 0 at 0, +-1 at +-pi/2, 2 at pi, and a half turn adds exactly 2
// (mod 4). The search only compares bearings with each other and with a half turn, so these
// comparisons give the same answers as with radians, at one division instead of an arctangent.
inline double pseudo_bearing(double y, double x) {
  const double sum = std::abs(x) + std::abs(y);
  if (sum == 0.0) return 0.0;
  const double a = y / sum;
  if (x >= 0.0) return a;
  return y >= 0.0 ? kHalfTurn - a : -kHalfTurn - a;
}

// The pseudo-angle difference wrapped into [-2, 2).
inline double wrap_half_turn(double difference) {
  while (difference >= kHalfTurn) difference -= kFullTurn;
  while (difference < -kHalfTurn) difference += kFullTurn;
  return difference;
}

// up_bigger[i]: the first j > i with a larger range (n if none), and so on. Amortised O(n):
// a run of points that are not larger than i is skipped with their own table entries.
void build_jump_tables(const TargetIndex& t) {
  if (t.jump_tables_built) return;
  t.jump_tables_built = true;
  const int n = t.size();
  const auto& r = t.ranges;
  t.up_bigger.assign(n, n);
  t.up_smaller.assign(n, n);
  t.down_bigger.assign(n, kNone);
  t.down_smaller.assign(n, kNone);
  for (int i = n - 1; i >= 0; --i) {
    int j = i + 1;
    while (j < n && r[j] <= r[i]) j = t.up_bigger[j];
    t.up_bigger[i] = j;
    j = i + 1;
    while (j < n && r[j] >= r[i]) j = t.up_smaller[j];
    t.up_smaller[i] = j;
  }
  for (int i = 0; i < n; ++i) {
    int j = i - 1;
    while (j >= 0 && r[j] <= r[i]) j = t.down_bigger[j];
    t.down_bigger[i] = j;
    j = i - 1;
    while (j >= 0 && r[j] >= r[i]) j = t.down_smaller[j];
    t.down_smaller[i] = j;
  }
}

// Bearings unwrapped along the scan; the projective search needs them strictly increasing
// over less than a full turn.
void unwrap_bearings(TargetIndex& t) {
  const int n = t.size();
  t.bearings.resize(n);
  t.ordered = n >= 2;
  double previous = 0.0;
  for (int k = 0; k < n; ++k) {
    const double raw = pseudo_bearing(t.points[k].y(), t.points[k].x());
    t.bearings[k] = k == 0 ? raw : t.bearings[k - 1] + wrap_half_turn(raw - previous);
    if (k > 0 && !(t.bearings[k] > t.bearings[k - 1])) t.ordered = false;
    previous = raw;
  }
  if (n >= 2 && t.bearings[n - 1] - t.bearings[0] >= kFullTurn) t.ordered = false;
  if (n >= 1) t.gap_center = t.bearings[n - 1] + 0.5 * (kFullTurn - (t.bearings[n - 1] - t.bearings[0]));
}

// ---------------------------------------------------------------------------------------------
// The walk. For a query p (range rho, bearing theta) and a target point j at bearing offset
// delta_j = bearing_j - theta in [0, pi], every point k further up with delta_k in [delta_j, pi]
// is at least rho g(delta_j) from p, g = sin below pi/2 and 1 above (the distance from p to the
// ray of bearing k). Points beyond a half turn are at least rho g(delta_max) away, g = 1 up to
// 3 pi / 2, |sin| above (`tail`). And a jump is exact: if r_j >= rho cos(delta_j) every point up
// to up_smaller[j] (ranges >= r_j) is no closer than j, else every point up to up_bigger[j]
// (ranges <= r_j) is no closer (d^2 = r^2 + rho^2 - 2 r rho cos delta is monotone in r on
// either side of rho cos delta, and grows with delta). CSM jumps on r_j < rho instead and stops
// on the same sine bound.
//
// The clearance: every point but the best one is either visited (its distance counts), skipped
// by a jump from a visited point that is not the best (no closer than that point; the walk
// never jumps from the current best, it steps instead), or beyond a side's stopping bound.
struct Query {
  Point2 p;
  double rho2 = 0.0;        // m^2, |p|^2
  double theta = 0.0;       // pseudo-angle, unwrapped into the target's bearings
  double tail_up2 = 0.0;    // m^2, bound for the points more than a half turn up
  double tail_down2 = 0.0;  // m^2, the same down
};

// (rho g(delta))^2 for the bearing vector u: (p x u)^2 in front of p, rho^2 behind.
inline double ray_distance_squared(const Point2& p, double rho2, const Point2& u) {
  const double cross = p.x() * u.y() - p.y() * u.x();
  return p.dot(u) > 0.0 ? cross * cross : rho2;
}

Query make_query(const TargetIndex& t, const Point2& p) {
  Query q{p, p.squaredNorm()};
  q.theta = pseudo_bearing(p.y(), p.x());
  while (q.theta > t.gap_center) q.theta -= kFullTurn;
  while (q.theta <= t.gap_center - kFullTurn) q.theta += kFullTurn;
  q.tail_up2 = t.bearings.back() - q.theta > kHalfTurn ? ray_distance_squared(p, q.rho2, t.directions.back()) : kInfinity;
  q.tail_down2 = q.theta - t.bearings.front() > kHalfTurn ? ray_distance_squared(p, q.rho2, t.directions.front()) : kInfinity;
  return q;
}

struct Walk {
  double best;              // m^2, the closest distance so far (max_distance^2 at first)
  int index = kNone;        // its point
  double others = kInfinity;  // m^2, lower bound for every point but `index` visited or ruled out

  void visit(double d2, int j) {
    if (d2 < best) {
      if (index != kNone) others = std::min(others, best);
      best = d2;
      index = j;
    } else {
      others = std::min(others, d2);
    }
  }
  bool stop(double bound) {  // the rest of a side is at least sqrt(bound) away
    if (bound < best) return false;
    others = std::min(others, bound);
    return true;
  }
};

// One step of the walk on one side (kDirection +1 up, -1 down) from point j, with or without
// the jump tables; false when the side is done. Inlined: it is the innermost loop of the matcher.
template <int kDirection, bool kJumps>
[[gnu::always_inline]] inline bool walk_step(const TargetIndex& t, const Query& q, int& j, Walk& walk) {
  const int n = t.size();
  if (kDirection > 0 ? j >= n : j < 0) return false;
  const Point2& point = t.points[j];
  walk.visit((point - q.p).squaredNorm(), j);
  const double delta = kDirection * (t.bearings[j] - q.theta);
  if (delta < 0.0) {  // not yet past the query's bearing: no bound holds here
    j += kDirection;
    return true;
  }
  const double tail = kDirection > 0 ? q.tail_up2 : q.tail_down2;
  if (!(delta <= kHalfTurn)) {  // more than a half turn away: only the tail bound holds
    if (walk.stop(tail)) return false;
    j += kDirection;
    return true;
  }
  if (walk.stop(std::min(tail, ray_distance_squared(q.p, q.rho2, t.directions[j])))) return false;
  // Plain steps without the tables, and none but steps from the best: the clearance needs the
  // points a jump would skip.
  if (!kJumps || walk.index == j) {
    j += kDirection;
    return true;
  }
  const bool farther = t.ranges[j] * t.ranges[j] >= q.p.dot(point);  // r_j >= rho cos(delta_j)
  const int jump = kDirection > 0 ? (farther ? t.up_smaller[j] : t.up_bigger[j])
                                  : (farther ? t.down_smaller[j] : t.down_bigger[j]);
  if (kDirection > 0 ? jump >= n : jump < 0) {
    const int last = kDirection > 0 ? n - 1 : 0;
    if (kDirection * (t.bearings[last] - q.theta) <= kHalfTurn) return false;  // the rest is no closer than j
    j += kDirection;
  } else {
    j = kDirection * (t.bearings[jump] - q.theta) <= kHalfTurn ? jump : j + kDirection;
  }
  return true;
}

// The bound (squared) for the points beyond point j on one side (kDirection), when j is at or
// past the query's bearing; NaN when it is not (no bound holds there).
template <int kDirection>
double beyond_bound(const TargetIndex& t, const Query& q, int j) {
  if (kDirection > 0 ? j + 1 >= t.size() : j <= 0) return kInfinity;  // nothing beyond
  const double delta = kDirection * (t.bearings[j] - q.theta);
  const double tail = kDirection > 0 ? q.tail_up2 : q.tail_down2;
  if (!(delta >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  if (!(delta <= kHalfTurn)) return tail;
  return std::min(tail, ray_distance_squared(q.p, q.rho2, t.directions[j]));
}

// The fast path: every point in a window of the scan around `center`, without a branch, then
// the bounds for the points outside it. True (and j1, clearance) when those bounds settle it;
// false leaves it to the walk.
constexpr int kWindowHalfWidth = 3;

bool window_closest(const TargetIndex& t, const Query& q, int center, double max_squared, int& index,
                    double& clearance) {
  const int lo = std::max(0, center - kWindowHalfWidth);
  const int hi = std::min(t.size() - 1, center + kWindowHalfWidth);
  const double up = beyond_bound<+1>(t, q, hi);
  const double down = beyond_bound<-1>(t, q, lo);
  if (!(up >= 0.0 && down >= 0.0)) return false;  // a window edge short of p's bearing
  const double outside = std::min(up, down);
  // Branch-free (the comparisons are data-dependent): the second smallest takes the larger of
  // the best so far and d2, minsd / maxsd / cmov.
  double best = kInfinity, second = kInfinity;
  int best_index = kNone;
  for (int k = lo; k <= hi; ++k) {
    const double d2 = (t.points[k] - q.p).squaredNorm();
    best_index = d2 < best ? k : best_index;
    second = std::min(second, std::max(best, d2));
    best = std::min(best, d2);
  }
  if (outside < std::min(best, max_squared)) return false;  // a point outside may be closer
  second = std::min(second, outside);
  if (best >= max_squared) {  // nothing within reach
    second = std::min(second, best);
    best_index = kNone;
  }
  index = best_index;
  clearance = std::sqrt(second);
  return true;
}

// Both sides of the walk, in turns while both are open: at most `rounds` turns; true when both
// sides are done.
struct WalkSides {
  int up = 0, down = 0;  // the next point on either side
  bool up_open = true, down_open = true;
};

template <bool kJumps>
bool walk_sides(const TargetIndex& t, const Query& q, WalkSides& s, Walk& walk, int rounds) {
  for (; rounds > 0 && (s.up_open || s.down_open); --rounds) {
    if (s.up_open) s.up_open = walk_step<+1, kJumps>(t, q, s.up, walk);
    if (s.down_open) s.down_open = walk_step<-1, kJumps>(t, q, s.down, walk);
  }
  return !(s.up_open || s.down_open);
}

// Walks are mostly a few steps (the window settles most queries, and a walk starts near p's
// bearing), so the jump tables, O(n) per target, are built only for a walk longer than this.
constexpr int kStepsBeforeJumps = 16;

// The closest target point strictly within sqrt(max_squared) of p, starting at `hint` (the
// previous iteration's match) or else at p's bearing; `clearance` (m) as in the header.
int projective_closest(const TargetIndex& t, const Point2& p, int hint, double max_squared, double& clearance) {
  clearance = 0.0;
  if (!(p.squaredNorm() >= kMinRange * kMinRange)) return kNone;
  const Query q = make_query(t, p);
  int index = kNone;
  if (hint >= 0 && hint < t.size() && window_closest(t, q, hint, max_squared, index, clearance)) return index;
  int start = hint;
  // A start far off p's bearing would be walked to point by point: bisect instead.
  constexpr double kFarStart = 0.1;  // pseudo-angle, about 9 degrees
  if (start < 0 || start >= t.size() || std::abs(t.bearings[start] - q.theta) > kFarStart) {
    start = static_cast<int>(std::lower_bound(t.bearings.begin(), t.bearings.end(), q.theta) - t.bearings.begin());
  }
  Walk walk{max_squared};
  WalkSides sides{.up = start, .down = start - 1};
  if (!walk_sides<false>(t, q, sides, walk, kStepsBeforeJumps)) {
    build_jump_tables(t);
    walk_sides<true>(t, q, sides, walk, std::numeric_limits<int>::max());
  }
  clearance = std::sqrt(walk.others);
  return walk.index;
}

// The closest target point by kd-tree, and the certificate of the header: the second closest
// point's distance (every point's, the closest one's, when that is out of reach).
int kd_tree_closest(const TargetIndex& t, const Point2& p, double max_squared, double& clearance) {
  thread_local std::vector<Neighbor> closest;
  const std::size_t found = t.tree->nearest_k(p, 2, closest);
  if (found == 0) {
    clearance = kInfinity;
    return kNone;
  }
  if (closest[0].squared_distance >= max_squared) {
    clearance = std::sqrt(closest[0].squared_distance);
    return kNone;
  }
  clearance = found > 1 ? std::sqrt(closest[1].squared_distance) : kInfinity;
  return static_cast<int>(closest[0].index);
}

}  // namespace

TargetIndex prepare_target(const PointCloud2& target, PlIcpSearch search) {
  TargetIndex t;
  prepare_target(target, search, t);
  return t;
}

void prepare_target(const PointCloud2& target, PlIcpSearch search, TargetIndex& t) {
  t.original.clear();
  t.points.clear();
  t.directions.clear();
  t.ranges.clear();
  t.ordered = false;
  t.jump_tables_built = false;
  t.gap_center = 0.0;
  t.tree.reset();
  t.original.reserve(target.size());
  t.points.reserve(target.size());
  t.directions.reserve(target.size());
  t.ranges.reserve(target.size());
  for (std::size_t i = 0; i < target.size(); ++i) {
    const double range = target.points[i].norm();
    if (!(range >= kMinRange) || !std::isfinite(range)) continue;
    t.original.push_back(i);
    t.points.push_back(target.points[i]);
    t.directions.push_back(target.points[i] * (1.0 / range));
    t.ranges.push_back(range);
  }
  const std::size_t segments = t.points.empty() ? 0 : t.points.size() - 1;
  t.segment_lengths.resize(segments);
  t.segment_normals.resize(segments);
  for (std::size_t k = 0; k < segments; ++k) {
    const Point2 along = t.points[k + 1] - t.points[k];
    const double length = along.norm();
    t.segment_lengths[k] = length;
    t.segment_normals[k] = length > 0.0 ? Point2(Point2(-along.y(), along.x()) * (1.0 / length)) : Point2::Zero();
  }
  unwrap_bearings(t);
  if (!(search == PlIcpSearch::kProjective && t.ordered)) {
    t.ordered = false;
    t.tree = std::make_unique<KdTree2>(t.points);
  }
}

int search_and_track(const TargetIndex& t, const Point2& p, double max_distance, TrackedNearest& tracked, int start) {
  tracked.anchor = p;
  if (!t.ordered) {
    tracked.index = kd_tree_closest(t, p, max_distance * max_distance, tracked.clearance);
  } else {
    const int hint = tracked.index != kNone ? tracked.index : start;
    tracked.index = projective_closest(t, p, hint, max_distance * max_distance, tracked.clearance);
  }
  return tracked.index;
}

}  // namespace slam2d::pl_icp_detail
