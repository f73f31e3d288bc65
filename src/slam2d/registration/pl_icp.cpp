// PL-ICP: A. Censi, "An ICP variant using a point-to-line metric", ICRA 2008. The equation
// numbers are those listed in pl_icp.hpp.

#include "slam2d/registration/pl_icp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/kd_tree.hpp"

namespace slam2d {
namespace {

constexpr double kPi = std::numbers::pi;
// The search compares bearings as pseudo-angles (pseudo_bearing below): a half turn is 2.
constexpr double kHalfTurn = 2.0;
constexpr double kFullTurn = 4.0;
constexpr double kMinRange = 1e-3;  // m: points this close to the sensor have no bearing
constexpr int kNone = -1;

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

// ---------------------------------------------------------------------------------------------
// The target, prepared once per match: its usable points in scan order with their ranges, unit
// bearing vectors, unwrapped bearings and the jump tables of the projective search.
struct TargetIndex {
  std::vector<std::size_t> original;  // cloud index of each usable point
  std::vector<Point2> points;         // m
  std::vector<Point2> directions;     // unit bearing vectors
  std::vector<double> ranges;         // m
  std::vector<double> bearings;       // pseudo-angles, unwrapped, strictly increasing when `ordered`
  std::vector<Point2> segment_normals;  // unit normal of the segment (k, k + 1)
  std::vector<double> segment_lengths;  // m, |p_{k+1} - p_k|
  std::vector<int> up_bigger, up_smaller, down_bigger, down_smaller;
  bool ordered = false;               // bearings increase over less than a full turn
  double gap_center = 0.0;            // pseudo-angle, the middle of the unscanned sector
  std::unique_ptr<KdTree2> tree;      // kd-tree search (config, or an unordered target)

  int size() const { return static_cast<int>(points.size()); }
};

// up_bigger[i]: the first j > i with a larger range (n if none), and so on. Amortised O(n):
// a run of points that are not larger than i is skipped with their own table entries.
void build_jump_tables(TargetIndex& t) {
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

TargetIndex prepare_target(const PointCloud2& target, PlIcpSearch search) {
  TargetIndex t;
  t.original.reserve(target.size());
  t.points.reserve(target.size());
  t.directions.reserve(target.size());
  t.ranges.reserve(target.size());
  t.segment_lengths.reserve(target.size());
  t.segment_normals.reserve(target.size());
  for (std::size_t i = 0; i < target.size(); ++i) {
    const double range = target.points[i].norm();
    if (!(range >= kMinRange) || !std::isfinite(range)) continue;
    t.original.push_back(i);
    t.points.push_back(target.points[i]);
    t.directions.push_back(target.points[i] / range);
    t.ranges.push_back(range);
  }
  for (std::size_t k = 0; k + 1 < t.points.size(); ++k) {
    const Point2 along = t.points[k + 1] - t.points[k];
    const double length = along.norm();
    t.segment_lengths.push_back(length);
    t.segment_normals.push_back(length > 0.0 ? Point2(-along.y() / length, along.x() / length) : Point2::Zero());
  }
  unwrap_bearings(t);
  if (search == PlIcpSearch::kProjective && t.ordered) {
    build_jump_tables(t);
  } else {
    t.ordered = false;
    t.tree = std::make_unique<KdTree2>(t.points);
  }
  return t;
}

// ---------------------------------------------------------------------------------------------
// Eq. (2), projective search. For a query p (range rho, bearing theta) and a target point j at
// bearing offset delta_j = bearing_j - theta in [0, pi], every point k further up with
// delta_k in [delta_j, pi] is at least rho g(delta_j) from p, g = sin below pi/2 and 1 above
// (the distance from p to the ray of bearing k). Points beyond a half turn are at least
// rho g(delta_max) away, g = 1 up to 3 pi / 2, |sin| above (`tail`). And a jump is exact: if
// r_j >= rho cos(delta_j) every point up to up_smaller[j] (ranges >= r_j) is no closer than j,
// else every point up to up_bigger[j] (ranges <= r_j) is no closer (d^2 = r^2 + rho^2 -
// 2 r rho cos delta is monotone in r on either side of rho cos delta, and grows with delta).
// CSM jumps on r_j < rho instead and stops on the same sine bound.
struct Query {
  Point2 p;
  double rho2 = 0.0;       // m^2, |p|^2
  double theta = 0.0;      // pseudo-angle, unwrapped into the target's bearings
  double tail_up2 = 0.0;   // m^2, bound for the points more than a half turn up
  double tail_down2 = 0.0; // m^2, the same down
};

// (rho g(delta))^2 for the bearing vector u: (p x u)^2 in front of p, rho^2 behind.
double ray_distance_squared(const Point2& p, double rho2, const Point2& u) {
  const double cross = p.x() * u.y() - p.y() * u.x();
  return p.dot(u) > 0.0 ? cross * cross : rho2;
}

Query make_query(const TargetIndex& t, const Point2& p) {
  Query q{p, p.squaredNorm()};
  q.theta = pseudo_bearing(p.y(), p.x());
  while (q.theta > t.gap_center) q.theta -= kFullTurn;
  while (q.theta <= t.gap_center - kFullTurn) q.theta += kFullTurn;
  constexpr double kNoBound = std::numeric_limits<double>::infinity();
  q.tail_up2 = t.bearings.back() - q.theta > kHalfTurn ? ray_distance_squared(p, q.rho2, t.directions.back()) : kNoBound;
  q.tail_down2 = q.theta - t.bearings.front() > kHalfTurn ? ray_distance_squared(p, q.rho2, t.directions.front()) : kNoBound;
  return q;
}

struct Best {
  double squared_distance;  // m^2
  int index = kNone;
};

// One step of the walk on one side (kDirection +1 up, -1 down) from point j; false when the
// side is done. Inlined: it is the innermost loop of the matcher.
template <int kDirection>
[[gnu::always_inline]] inline bool walk_step(const TargetIndex& t, const Query& q, int& j, Best& best) {
  const int n = t.size();
  if (kDirection > 0 ? j >= n : j < 0) return false;
  const Point2& point = t.points[j];
  const double d2 = (point - q.p).squaredNorm();
  if (d2 < best.squared_distance) best = {d2, j};
  const double delta = kDirection * (t.bearings[j] - q.theta);
  if (delta < 0.0) {  // not yet past the query's bearing: no bound holds here
    j += kDirection;
    return true;
  }
  const double tail = kDirection > 0 ? q.tail_up2 : q.tail_down2;
  if (!(delta <= kHalfTurn)) {  // more than a half turn away: only the tail bound holds
    if (tail >= best.squared_distance) return false;
    j += kDirection;
    return true;
  }
  if (std::min(tail, ray_distance_squared(q.p, q.rho2, t.directions[j])) >= best.squared_distance) return false;
  const bool farther = t.ranges[j] * t.ranges[j] >= q.p.dot(point);  // r_j >= rho cos(delta_j)
  const int jump = kDirection > 0 ? (farther ? t.up_smaller[j] : t.up_bigger[j])
                                  : (farther ? t.down_smaller[j] : t.down_bigger[j]);
  if (kDirection > 0 ? jump >= n : jump < 0) {
    const int last = kDirection > 0 ? n - 1 : 0;
    if (kDirection * (t.bearings[last] - q.theta) <= kHalfTurn) return false;  // the rest is no closer
    j += kDirection;
  } else {
    j = kDirection * (t.bearings[jump] - q.theta) <= kHalfTurn ? jump : j + kDirection;
  }
  return true;
}

// The closest target point within sqrt(max_squared) of p, starting at `hint` (the previous
// iteration's match) or else at p's bearing.
int projective_closest(const TargetIndex& t, const Point2& p, int hint, double max_squared) {
  if (!(p.squaredNorm() >= kMinRange * kMinRange)) return kNone;
  const Query q = make_query(t, p);
  int start = hint;
  if (start < 0 || start >= t.size()) {
    start = static_cast<int>(std::lower_bound(t.bearings.begin(), t.bearings.end(), q.theta) - t.bearings.begin());
  }
  Best best{max_squared};
  int up = start;
  int down = start - 1;
  bool up_open = true;
  bool down_open = true;
  while (up_open && down_open) {
    up_open = walk_step<+1>(t, q, up, best);
    down_open = walk_step<-1>(t, q, down, best);
  }
  while (up_open) up_open = walk_step<+1>(t, q, up, best);
  while (down_open) down_open = walk_step<-1>(t, q, down, best);
  return best.index;
}

int kd_tree_closest(const TargetIndex& t, const Point2& p, double max_squared) {
  const Neighbor nearest = t.tree->nearest(p);
  if (nearest.index >= t.points.size() || nearest.squared_distance >= max_squared) return kNone;
  return static_cast<int>(nearest.index);
}

// The closer of j1's two scan neighbours.
int better_neighbour(const TargetIndex& t, const Point2& p, int j1) {
  const int below = j1 - 1;
  const int above = j1 + 1;
  if (below < 0) return above < t.size() ? above : kNone;
  if (above >= t.size()) return below;
  return (t.points[below] - p).squaredNorm() <= (t.points[above] - p).squaredNorm() ? below : above;
}

// ---------------------------------------------------------------------------------------------
// Adds w (n^T (R p + t - q))^2 to the quadratic form of Eq. (4) (PointToLineProblem::add).
[[gnu::always_inline]] inline void add_term(PointToLineProblem& problem, const Point2& p, const Point2& q, const Point2& n,
                                            double w) {
  // n^T (R p + t - q) = a^T x - n^T q with a = (n_x, n_y, n^T p, n^T J p), J p = (-p_y, p_x).
  const Eigen::Vector4d a(n.x(), n.y(), n.dot(p), n.x() * (-p.y()) + n.y() * p.x());
  const double b = n.dot(q);
  problem.M += w * a * a.transpose();
  problem.g -= 2.0 * w * b * a;
  problem.c += w * b * b;
  ++problem.terms;
}

// Per source point, per iteration.
struct SourcePair {
  Point2 moved = Point2::Zero();   // Eq. (1), p_i^w
  Point2 normal = Point2::Zero();  // unit normal of the segment
  double distance = 0.0;           // m, from p_i^w to the line of its segment
  int j1 = kNone, j2 = kNone;      // target (index) points of the segment, kNone: no pair
  int hint = kNone;                // the previous iteration's j1

  bool paired() const { return j1 != kNone && j2 != kNone; }
  void drop() { j2 = kNone; }
};

// Per-iteration state, sized once before the loop (no allocation inside it).
struct Workspace {
  std::vector<SourcePair> pairs;   // one per source point
  std::vector<double> quantiles;   // scratch for Eq. (3)
  std::vector<double> closest;     // m, per target point: its closest source point (doubles)

  Workspace(std::size_t sources, std::size_t targets) : pairs(sources), closest(targets) { quantiles.reserve(sources); }
};

// Eq. (1) and (2), fused: move each source point, find its segment and its distance to it.
void find_correspondences(const TargetIndex& t, const PointCloud2& source, const SE2& T, const PlIcpConfig& config,
                          Workspace& ws) {
  const double max_squared = config.max_correspondence_distance * config.max_correspondence_distance;
  const Eigen::Matrix2d R = T.rotation();
  for (std::size_t i = 0; i < ws.pairs.size(); ++i) {
    SourcePair& s = ws.pairs[i];
    s.moved = R * source.points[i] + T.translation();  // Eq. (1)
    s.j1 = t.ordered ? projective_closest(t, s.moved, s.hint, max_squared) : kd_tree_closest(t, s.moved, max_squared);
    s.j2 = kNone;
    if (s.j1 == kNone) continue;
    s.hint = s.j1;
    s.j2 = better_neighbour(t, s.moved, s.j1);
    if (s.j2 == kNone) continue;
    s.normal = t.segment_normals[std::min(s.j1, s.j2)];
    s.distance = std::abs(s.normal.dot(s.moved - t.points[s.j1]));  // to the line, the metric of Eq. (4)
  }
}

// Drops pairs whose segment is too long and, of the source points sharing a j1, all but the
// closest; collects the distances of the rest into ws.quantiles.
void drop_long_segments_and_doubles(const TargetIndex& t, const PlIcpConfig& config, Workspace& ws) {
  const bool doubles = config.outliers_remove_doubles;
  if (doubles) std::fill(ws.closest.begin(), ws.closest.end(), std::numeric_limits<double>::infinity());
  for (SourcePair& s : ws.pairs) {
    if (!s.paired()) continue;
    if (t.segment_lengths[std::min(s.j1, s.j2)] > config.max_segment_length) {
      s.drop();
    } else if (doubles) {
      ws.closest[s.j1] = std::min(ws.closest[s.j1], s.distance);
    }
  }
  ws.quantiles.clear();
  for (SourcePair& s : ws.pairs) {
    if (!s.paired()) continue;
    if (doubles && s.distance > ws.closest[s.j1]) {
      s.drop();
    } else {
      ws.quantiles.push_back(s.distance);
    }
  }
}

// Eq. (3): min(e_(maxPerc), mult * e_(order)), e_(f) the value at fraction f of the sorted
// distances (CSM's hoare_selection at floor(n f)); one selection for the lower fraction, a
// second on the part above it for the higher. `values` is non-empty and gets reordered.
double trimming_limit(const PlIcpConfig& config, std::vector<double>& values) {
  const std::size_t n = values.size();
  const auto rank = [n](double fraction) { return std::min(n - 1, static_cast<std::size_t>(fraction * static_cast<double>(n))); };
  const std::size_t trimmed = rank(config.outliers_max_fraction);
  const std::size_t adaptive = rank(config.outliers_adaptive_order);
  const auto lower = values.begin() + static_cast<std::ptrdiff_t>(std::min(trimmed, adaptive));
  const auto upper = values.begin() + static_cast<std::ptrdiff_t>(std::max(trimmed, adaptive));
  std::nth_element(values.begin(), lower, values.end());
  if (upper != lower) std::nth_element(lower + 1, upper, values.end());
  return std::min(values[trimmed], config.outliers_adaptive_mult * values[adaptive]);
}

// The pairs kept, and a hash of the association (j1, j2 per source point): when an association
// comes back, the estimate it gives comes back too, so the loop has reached a fixed point or a
// cycle (CSM's loop detection).
struct Association {
  std::size_t kept = 0;
  std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a
};

// Eq. (3) and the other rejections: long segments, doubles, trimming.
Association reject_outliers(const TargetIndex& t, const PlIcpConfig& config, Workspace& ws) {
  drop_long_segments_and_doubles(t, config, ws);
  Association association;
  if (ws.quantiles.empty()) return association;
  const double limit = trimming_limit(config, ws.quantiles);
  for (SourcePair& s : ws.pairs) {
    if (s.paired() && s.distance > limit) s.drop();
    std::uint64_t pair = ~std::uint64_t{0};
    if (s.paired()) {
      ++association.kept;
      pair = (static_cast<std::uint64_t>(s.j1) << 32) ^ static_cast<std::uint32_t>(s.j2);
    }
    association.hash = (association.hash ^ pair) * 1099511628211ULL;
  }
  return association;
}

double weight(const PointCloud2& source, std::size_t i) { return source.has_weights() ? source.weights[i] : 1.0; }

PointToLineProblem build_problem(const TargetIndex& t, const PointCloud2& source, const Workspace& ws) {  // Eq. (4)
  PointToLineProblem problem;
  for (std::size_t i = 0; i < ws.pairs.size(); ++i) {
    const SourcePair& s = ws.pairs[i];
    if (s.paired()) add_term(problem, s.moved, t.points[s.j1], s.normal, weight(source, i));
  }
  return problem;
}

// Censi 2007, Eq. (6), for the point-to-line metric in closed form (the same quantity as
// registration/covariance.hpp's censi_covariance, which takes it by finite differences and is
// too slow for this matcher's budget; pl_icp_test checks that they agree). With the moved point
// m = R p + t, the unit normal n of the segment d = q2 - q1 (n = J d / |d|, J the +90 deg
// rotation) and e = n^T (m - q1), the cost is sum w e^2, its gradient sum 2 w e a with
// a = (n, n^T J R p), and:
//   d2J/dx2   = sum 2 w (a a^T + e da/dx),    da/dx = e_theta e_theta^T (-n^T R p)
//   d2J/dz dx = 2 w (de/dz a + e da/dz)       for the range z of p, q1 and q2 (each moves its
//                                             point along its bearing u): dn/dq = -+(n^T dq / |d|) d/|d|.
// The covariance is H^-1 (sum_z d2J/dz dx d2J/dz dx^T) sigma^2 H^-1: a source point is in one
// pair, so its column is added at once; a target point's column gathers over its pairs.
Covariance3 point_to_line_covariance(const TargetIndex& t, const PointCloud2& source, const SE2& T,
                                     const Workspace& ws, double range_sigma) {
  const Eigen::Matrix2d R = T.rotation();
  const auto perpendicular = [](const Point2& v) { return Point2(-v.y(), v.x()); };
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  std::vector<Eigen::Vector3d> target_columns(t.points.size(), Eigen::Vector3d::Zero());
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < ws.pairs.size(); ++i) {
    const SourcePair& s = ws.pairs[i];
    if (!s.paired()) continue;
    ++pairs;
    const Point2& q1 = t.points[s.j1];
    const Point2 d = t.points[s.j2] - q1;
    const double length = d.norm();
    if (!(length > 1e-12)) continue;
    const Point2 along = d / length;
    const Point2 n = perpendicular(along);
    const Point2& p = source.points[i];
    const Point2 Rp = R * p;
    const Point2 dRp = perpendicular(Rp);  // d(R p)/d theta
    const Point2 offset = Rp + T.translation() - q1;
    const double e = n.dot(offset);
    const double w2 = 2.0 * weight(source, i);
    const Eigen::Vector3d a(n.x(), n.y(), n.dot(dRp));
    H += w2 * a * a.transpose();
    H(2, 2) -= w2 * e * n.dot(Rp);
    const auto column = [&](double de, const Point2& dn, double dn_theta) -> Eigen::Vector3d {
      return w2 * (de * a + e * Eigen::Vector3d(dn.x(), dn.y(), dn_theta));
    };
    const double range = p.norm();
    const Point2 Ru = range > 1e-12 ? Point2(R * (p / range)) : Point2::Zero();
    const Eigen::Vector3d source_column = column(n.dot(Ru), Point2::Zero(), n.dot(perpendicular(Ru)));
    spread += source_column * source_column.transpose();
    const double beta1 = n.dot(t.directions[s.j1]);
    const Point2 dn1 = (beta1 / length) * along;
    target_columns[s.j1] += column(beta1 * (along.dot(offset) / length - 1.0), dn1, dn1.dot(dRp));
    const Point2 dn2 = -(n.dot(t.directions[s.j2]) / length) * along;
    target_columns[s.j2] += column(dn2.dot(offset), dn2, dn2.dot(dRp));
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
  const double scale = H.diagonal().cwiseAbs().maxCoeff();
  if (pairs < 3 || ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(scale > 0.0) ||
      ldlt.vectorD().minCoeff() <= 1e-12 * scale) {
    return Covariance3::Identity() * 1e6;
  }
  const Eigen::Matrix3d H_inverse = ldlt.solve(Eigen::Matrix3d::Identity());
  for (const Eigen::Vector3d& c : target_columns) spread += c * c.transpose();
  spread *= range_sigma * range_sigma;
  const Covariance3 covariance = H_inverse * spread * H_inverse;
  if (!covariance.allFinite()) return Covariance3::Identity() * 1e6;
  return make_positive_definite(0.5 * (covariance + covariance.transpose()), 1e-18);
}

// The unit normal of the total least squares line through target point k and up to
// kNormalHalfWindow neighbours on either side (stopping at gaps longer than max_gap), for the
// Fisher information: a two-point segment's normal is too noisy near the sensor to tell a
// corridor from a room. Closed form: the eigenvector of the scatter's smaller eigenvalue.
constexpr int kNormalHalfWindow = 3;

Point2 fitted_normal(const TargetIndex& t, int k, double max_gap) {
  int lo = k, hi = k;
  while (lo > 0 && k - lo < kNormalHalfWindow && t.segment_lengths[lo - 1] <= max_gap) --lo;
  while (hi + 1 < t.size() && hi - k < kNormalHalfWindow && t.segment_lengths[hi] <= max_gap) ++hi;
  if (hi - lo < 2) return Point2::Zero();
  Point2 mean = Point2::Zero();
  for (int j = lo; j <= hi; ++j) mean += t.points[j];
  mean /= static_cast<double>(hi - lo + 1);
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (int j = lo; j <= hi; ++j) {
    const Point2 v = t.points[j] - mean;
    sxx += v.x() * v.x();
    sxy += v.x() * v.y();
    syy += v.y() * v.y();
  }
  const double smallest = 0.5 * (sxx + syy) - std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
  const Point2 a(sxy, smallest - sxx), b(smallest - syy, sxy);
  const Point2 normal = a.squaredNorm() >= b.squaredNorm() ? a : b;
  return normal.squaredNorm() > 0.0 ? Point2(normal.normalized()) : Point2::Zero();
}

// Degeneracy (degeneracy.hpp) from the final pairs, with fitted normals at their j1: the Fisher
// information that analyze_degeneracy sums for these pairs, here without copying the target.
DegeneracyAnalysis pl_icp_degeneracy(const PointCloud2& source, const SE2& T, const TargetIndex& t,
                                     const Workspace& ws, const PlIcpConfig& config) {
  const DegeneracyConfig degeneracy{.range_sigma = config.range_sigma};
  const double inverse_variance = 1.0 / (config.range_sigma * config.range_sigma);
  const Eigen::Matrix2d R = T.rotation();
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  double squared_radius_sum = 0.0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < ws.pairs.size(); ++i) {
    const SourcePair& s = ws.pairs[i];
    if (!s.paired()) continue;
    const Point2 n = fitted_normal(t, s.j1, config.max_segment_length);
    if (!(n.squaredNorm() > 0.5)) continue;  // no fitted normal (has_normal)
    const Point2 Rp = R * source.points[i];
    const Eigen::Vector3d a(n.x(), n.y(), n.dot(Point2(-Rp.y(), Rp.x())));
    information += inverse_variance * a * a.transpose();
    squared_radius_sum += source.points[i].squaredNorm();
    ++used;
  }
  if (used < 3) {
    DegeneracyAnalysis analysis;
    analysis.information = information;
    analysis.weak_direction = Eigen::Vector3d::UnitX();
    return analysis;
  }
  return analyze_information(information, std::sqrt(squared_radius_sum / static_cast<double>(used)), degeneracy);
}

// The weighted RMS point-to-line distance of the pairs.
double rms_point_to_line(const PointCloud2& source, const Workspace& ws) {
  double sum = 0.0, weights = 0.0;
  for (std::size_t i = 0; i < ws.pairs.size(); ++i) {
    const SourcePair& s = ws.pairs[i];
    if (!s.paired()) continue;
    const double w = weight(source, i);
    sum += w * s.distance * s.distance;
    weights += w;
  }
  return weights > 0.0 ? std::sqrt(sum / weights) : 0.0;
}

// The result at the estimate: the association there (`associated_at_T`: the workspace holds it
// already), its covariance (Censi 2007), RMS residual and degeneracy.
MatchResult finish(const PointCloud2& source, const TargetIndex& t, const SE2& T, bool converged,
                   bool associated_at_T, int iterations, const PlIcpConfig& config, Workspace& ws) {
  if (!associated_at_T) {
    find_correspondences(t, source, T, config, ws);
    reject_outliers(t, config, ws);
  }
  const auto inliers = static_cast<std::size_t>(
      std::count_if(ws.pairs.begin(), ws.pairs.end(), [](const SourcePair& s) { return s.paired(); }));
  MatchResult result;
  result.T_target_source = T;
  result.iterations = iterations;
  result.inliers = inliers;
  const bool enough = inliers >= static_cast<std::size_t>(config.min_correspondences);
  result.converged = converged && enough;
  if (enough) {
    result.covariance = point_to_line_covariance(t, source, T, ws, config.range_sigma);
    result.residual = rms_point_to_line(source, ws);
  }
  apply(pl_icp_degeneracy(source, T, t, ws, config), result);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Quartic and cubic roots.

double polynomial(const double* coefficients, int degree, double x) {  // highest power first
  double value = coefficients[0];
  for (int k = 1; k <= degree; ++k) value = value * x + coefficients[k];
  return value;
}

double polynomial_derivative(const double* coefficients, int degree, double x) {
  double value = degree * coefficients[0];
  for (int k = 1; k < degree; ++k) value = value * x + (degree - k) * coefficients[k];
  return value;
}

// Newton steps that are kept only while they shrink |p(x)|.
double polish(const double* coefficients, int degree, double x) {
  double value = polynomial(coefficients, degree, x);
  for (int step = 0; step < 4 && value != 0.0; ++step) {
    const double slope = polynomial_derivative(coefficients, degree, x);
    if (slope == 0.0) break;
    const double next = x - value / slope;
    const double next_value = polynomial(coefficients, degree, next);
    if (!(std::abs(next_value) < std::abs(value))) break;
    x = next;
    value = next_value;
  }
  return x;
}

// The largest real root of x^3 + b x^2 + c x + d (Cardano, or the trigonometric form).
double largest_cubic_root(double b, double c, double d) {
  const double P = c - b * b / 3.0;
  const double Q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d;
  const double discriminant = 0.25 * Q * Q + P * P * P / 27.0;
  double y = 0.0;
  if (discriminant > 0.0) {
    const double root = std::sqrt(discriminant);
    y = std::cbrt(-0.5 * Q + root) + std::cbrt(-0.5 * Q - root);
  } else if (P < 0.0) {
    const double argument = std::clamp(1.5 * Q / P * std::sqrt(-3.0 / P), -1.0, 1.0);
    y = 2.0 * std::sqrt(-P / 3.0) * std::cos(std::acos(argument) / 3.0);
  }
  const double coefficients[4] = {1.0, b, c, d};
  return polish(coefficients, 3, y - b / 3.0);
}

// Real roots of y^2 + b y + c, appended.
void quadratic_roots(double b, double c, double* roots, int& count) {
  const double discriminant = b * b - 4.0 * c;
  if (discriminant < 0.0) return;
  const double root = std::sqrt(discriminant);
  roots[count++] = 0.5 * (-b + root);
  roots[count++] = 0.5 * (-b - root);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

int solve_quartic(double a, double b, double c, double d, double e, double roots[4]) {
  if (a == 0.0 || !std::isfinite(a)) return 0;
  const double A = b / a, B = c / a, C = d / a, D = e / a;  // monic x^4 + A x^3 + B x^2 + C x + D
  // Depressed by x = y - A/4: y^4 + p y^2 + q y + r.
  const double p = B - 3.0 * A * A / 8.0;
  const double q = C - A * B / 2.0 + A * A * A / 8.0;
  const double r = D - A * C / 4.0 + A * A * B / 16.0 - 3.0 * A * A * A * A / 256.0;
  int count = 0;
  double y[4];
  // Ferrari's resolvent: (y^2 + p/2 + m)^2 is a perfect square in y when
  // m^3 + p m^2 + (p^2/4 - r) m - q^2/8 = 0, which has a root m > 0 when q != 0.
  const double m = q == 0.0 ? 0.0 : largest_cubic_root(p, 0.25 * p * p - r, -0.125 * q * q);
  if (m > 0.0) {
    const double s = std::sqrt(2.0 * m);
    quadratic_roots(-s, 0.5 * p + m + q / (2.0 * s), y, count);
    quadratic_roots(s, 0.5 * p + m - q / (2.0 * s), y, count);
  } else {  // biquadratic: z = y^2, z^2 + p z + r = 0
    double z[2];
    int zs = 0;
    quadratic_roots(p, r, z, zs);
    for (int k = 0; k < zs; ++k) {
      if (z[k] < 0.0) continue;
      y[count++] = std::sqrt(z[k]);
      y[count++] = -std::sqrt(z[k]);
    }
  }
  const double coefficients[5] = {1.0, A, B, C, D};
  for (int k = 0; k < count; ++k) roots[k] = polish(coefficients, 4, y[k] - A / 4.0);
  return count;
}

double fast_atan2(double y, double x) {
  const double ax = std::abs(x);
  const double ay = std::abs(y);
  if (ax == 0.0 && ay == 0.0) return 0.0;
  const bool steep = ay > ax;
  const double z = steep ? ax / ay : ay / ax;  // in [0, 1]
  const double z2 = z * z;
  // Abramowitz & Stegun 4.4.49: |error| <= 2e-8 on [0, 1].
  double angle = z * (1.0 + z2 * (-0.3333314528 + z2 * (0.1999355085 + z2 * (-0.1420889944 + z2 * (0.1065626393 +
                 z2 * (-0.0752896400 + z2 * (0.0429096138 + z2 * (-0.0161657367 + z2 * 0.0028662257))))))));
  if (steep) angle = 0.5 * kPi - angle;
  if (x < 0.0) angle = kPi - angle;
  return y < 0.0 ? -angle : angle;
}

void PointToLineProblem::add(const Point2& p, const Point2& q, const Point2& n, double w) {
  add_term(*this, p, q, n, w);
}

double PointToLineProblem::cost(const SE2& T) const {
  const Eigen::Vector4d x(T.x(), T.y(), std::cos(T.theta()), std::sin(T.theta()));
  return x.dot(M * x) + g.dot(x) + c;
}

std::optional<SE2> minimize_point_to_line(const PointToLineProblem& problem) {
  const double scale = problem.M.trace();
  if (problem.terms == 0 || !(scale > 0.0) || !problem.M.allFinite() || !problem.g.allFinite()) return std::nullopt;
  Eigen::Matrix4d M = problem.M / scale;
  Eigen::Vector4d g = problem.g / scale;
  // The ridge eps (|t|^2 + (cos - 1)^2 + sin^2) toward the identity.
  constexpr double kRidge = 1e-12;
  M.diagonal().array() += kRidge;
  g(2) -= 2.0 * kRidge;
  // Eq. (5): t = -A^-1 (B x2 + g1 / 2) leaves x2^T S x2 + h^T x2 over the unit circle.
  const Eigen::Matrix2d A = M.topLeftCorner<2, 2>();
  const Eigen::Matrix2d B = M.topRightCorner<2, 2>();
  const Eigen::Matrix2d A_inverse = A.inverse();
  const Eigen::Matrix2d S = M.bottomRightCorner<2, 2>() - B.transpose() * A_inverse * B;
  const Eigen::Vector2d h = g.tail<2>() - B.transpose() * A_inverse * g.head<2>();
  // Eq. (6): det(S + l I)^2 - |(adj S + l I) h|^2 / 4 = 0.
  const double tau = S.trace();
  const double delta = S.determinant();
  Eigen::Matrix2d adjugate;
  adjugate << S(1, 1), -S(0, 1), -S(1, 0), S(0, 0);
  const Eigen::Vector2d u = adjugate * h;
  double lambdas[4];
  const int count = solve_quartic(1.0, 2.0 * tau, tau * tau + 2.0 * delta - 0.25 * h.squaredNorm(),
                                  2.0 * tau * delta - 0.5 * u.dot(h), delta * delta - 0.25 * u.squaredNorm(), lambdas);
  // The candidates: each root's x2 = -(S + l I)^-1 h / 2, and no rotation at all; least cost wins.
  Eigen::Vector2d best(1.0, 0.0);
  double best_cost = best.dot(S * best) + h.dot(best);
  for (int k = 0; k < count; ++k) {
    const Eigen::Matrix2d shifted = S + lambdas[k] * Eigen::Matrix2d::Identity();
    if (std::abs(shifted.determinant()) < 1e-300) continue;
    Eigen::Vector2d x2 = -0.5 * shifted.inverse() * h;
    if (!x2.allFinite() || x2.squaredNorm() < 1e-12) continue;
    x2.normalize();
    const double cost = x2.dot(S * x2) + h.dot(x2);
    if (cost < best_cost) {
      best_cost = cost;
      best = x2;
    }
  }
  const Eigen::Vector2d t = -A_inverse * (B * best + 0.5 * g.head<2>());
  if (!t.allFinite()) return std::nullopt;
  return SE2(t, std::atan2(best.y(), best.x()));
}

void validate(const PlIcpConfig& config) {
  check(config.max_iterations >= 1, "pl-icp: max_iterations must be >= 1");
  check(config.epsilon_xy >= 0.0 && std::isfinite(config.epsilon_xy), "pl-icp: epsilon_xy must be >= 0");
  check(config.epsilon_theta >= 0.0 && std::isfinite(config.epsilon_theta), "pl-icp: epsilon_theta must be >= 0");
  check(config.max_correspondence_distance > 0.0 && std::isfinite(config.max_correspondence_distance),
        "pl-icp: max_correspondence_distance must be > 0");
  check(config.max_segment_length > 0.0 && !std::isnan(config.max_segment_length),
        "pl-icp: max_segment_length must be > 0");
  check(config.outliers_max_fraction > 0.0 && config.outliers_max_fraction <= 1.0,
        "pl-icp: outliers_max_fraction must be in (0, 1]");
  check(config.outliers_adaptive_order > 0.0 && config.outliers_adaptive_order <= 1.0,
        "pl-icp: outliers_adaptive_order must be in (0, 1]");
  check(config.outliers_adaptive_mult > 0.0 && !std::isnan(config.outliers_adaptive_mult),
        "pl-icp: outliers_adaptive_mult must be > 0");
  check(config.search == PlIcpSearch::kProjective || config.search == PlIcpSearch::kKdTree,
        "pl-icp: unknown search");
  check(config.min_correspondences >= 3, "pl-icp: min_correspondences must be >= 3");
  check(config.range_sigma > 0.0 && std::isfinite(config.range_sigma), "pl-icp: range_sigma must be > 0");
}

std::vector<Correspondence> pl_icp_correspondences(const PointCloud2& target, const PointCloud2& source,
                                                   const SE2& T_target_source, const PlIcpConfig& config) {
  validate(config);
  const TargetIndex t = prepare_target(target, config.search);
  std::vector<Correspondence> pairs;
  if (t.size() == 0) return pairs;
  Workspace ws(source.size(), t.points.size());
  find_correspondences(t, source, T_target_source, config, ws);
  for (std::size_t i = 0; i < source.size(); ++i) {
    const SourcePair& s = ws.pairs[i];
    if (s.j1 == kNone) continue;
    pairs.push_back({i, t.original[s.j1], s.j2 == kNone ? kNoPoint : t.original[s.j2], 1.0});
  }
  return pairs;
}

MatchResult match_pl_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                         const PlIcpConfig& config) {
  validate(config);
  const TargetIndex t = prepare_target(target, config.search);
  if (t.size() < 3 || source.size() < 3) {  // nothing to match: the guess, unconverged, huge covariance
    MatchResult result;
    result.T_target_source = T_target_source_guess;
    apply(analyze_degeneracy(target, source, T_target_source_guess, {}), result);
    return result;
  }
  Workspace ws(source.size(), t.points.size());
  SE2 T = T_target_source_guess;
  bool converged = false;
  bool associated_at_T = false;
  int iteration = 0;
  std::vector<std::uint64_t> associations;
  associations.reserve(static_cast<std::size_t>(config.max_iterations));
  while (iteration < config.max_iterations && !converged) {
    ++iteration;
    find_correspondences(t, source, T, config, ws);                                             // Eq. (1)-(2)
    const Association association = reject_outliers(t, config, ws);                             // Eq. (3)
    if (association.kept < static_cast<std::size_t>(config.min_correspondences)) break;
    if (std::find(associations.begin(), associations.end(), association.hash) != associations.end()) {
      converged = true;  // a fixed point or a cycle of associations: nothing new to learn
      associated_at_T = true;
      break;
    }
    associations.push_back(association.hash);
    const std::optional<SE2> step = minimize_point_to_line(build_problem(t, source, ws));      // Eq. (4)-(6)
    if (!step) break;
    T = *step * T;
    converged = step->translation().norm() < config.epsilon_xy && std::abs(step->theta()) < config.epsilon_theta;  // Eq. (7)
  }
  return finish(source, t, T, converged, associated_at_T, iteration, config, ws);
}

}  // namespace slam2d
