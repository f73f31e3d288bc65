// SPDX-License-Identifier: BSD-3-Clause
// PL-ICP: A. Censi, "An ICP variant using a point-to-line metric", ICRA 2008. The equation
// numbers are those listed in pl_icp.hpp.

#include "slam2d/registration/pl_icp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "slam2d/core/covariance.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/detail/order_statistics.hpp"
#include "slam2d/registration/detail/pl_icp_search.hpp"

namespace slam2d {
namespace {

using namespace pl_icp_detail;

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
  double distance = 0.0;           // m, from p_i^w to the line of its segment: Eq. (4)'s residual
  double segment_distance = 0.0;   // m, from p_i^w to the segment itself: Eq. (3)'s trimming (CSM's)
  double point_distance = 0.0;     // m, from p_i^w to p_j1: the doubles (CSM's)
  int j1 = kNone, j2 = kNone;      // target (index) points of the segment, kNone: no pair
  TrackedNearest nearest;          // j1 across iterations, with its certificate

  bool paired() const { return j2 != kNone; }  // j2 is kNone whenever j1 is
};

// Sums of x, y, x^2, x y, y^2 over a run of points; as prefix sums over the target, the scatter of
// any window in O(1).
struct PointMoments {
  double x = 0.0, y = 0.0, xx = 0.0, xy = 0.0, yy = 0.0;

  PointMoments plus(const Point2& p) const {
    return {x + p.x(), y + p.y(), xx + p.x() * p.x(), xy + p.x() * p.y(), yy + p.y() * p.y()};
  }
  PointMoments minus(const PointMoments& o) const { return {x - o.x, y - o.y, xx - o.xx, xy - o.xy, yy - o.yy}; }
};

// Per-iteration state, sized once before the loop (no allocation inside it); match_pl_icp keeps
// one per thread across matches, with the prepared target.
struct Workspace {
  std::vector<SourcePair> pairs;   // one per source point
  std::vector<double> distances;   // Eq. (3)'s order statistics (BucketSelector), one slot per source point
  std::vector<int> inliers;        // the source points of the pairs kept, in order (inlier_count of them)
  std::size_t inlier_count = 0;
  std::vector<double> closest;     // m, per target point: its closest source point (doubles)
  std::vector<Eigen::Vector3d> target_columns;  // per target point, for the covariance
  std::vector<PointMoments> target_moments;     // prefix sums over the target, for the fitted normals
  std::vector<int> run_first, run_last;         // per target point: the ends of its run (no longer gap), for the same
  std::vector<std::uint8_t> distance_buckets;   // BucketSelector's buffers
  std::vector<double> selection_scratch;

  Workspace() = default;
  Workspace(std::size_t sources, std::size_t targets) { reset(sources, targets); }
  // Sized for a match, reusing the buffers: no allocation once they are large enough.
  void reset(std::size_t sources, std::size_t targets) {
    pairs.assign(sources, SourcePair{});
    distances.resize(sources);
    inliers.resize(sources);
    inlier_count = 0;
    closest.resize(targets);
    target_columns.resize(targets);
    target_moments.resize(targets + 1);
    run_first.resize(targets);
    run_last.resize(targets);
  }
};

// The upper triangle of a symmetric 3x3 sum of w a a^T.
struct SymmetricSum3 {
  double v[6] = {};  // (0,0), (0,1), (0,2), (1,1), (1,2), (2,2)

  void add(const Eigen::Vector3d& a, double w = 1.0) {
    const double w0 = w * a(0), w1 = w * a(1);
    v[0] += w0 * a(0);
    v[1] += w0 * a(1);
    v[2] += w0 * a(2);
    v[3] += w1 * a(1);
    v[4] += w1 * a(2);
    v[5] += w * a(2) * a(2);
  }
  Eigen::Matrix3d matrix() const {
    Eigen::Matrix3d m;
    m << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
    return m;
  }
};

// Eq. (1) and (2), fused: move each source point, find its segment and its distances to it.
// With `reject`, also the first rejections of Eq. (3), in the same pass: pairs whose segment is
// too long are dropped, and ws.closest gets, per target point, the smallest distance |p_i^w - p_j1|
// of the pairs on it (for the doubles). (j2 != kNone implies j1 != kNone: paired() tests j2 alone.)
template <bool kReject>
void find_correspondences(const TargetIndex& t, const PointCloud2& source, const SE2& T, const PlIcpConfig& config,
                          Workspace& ws) {
  const Eigen::Matrix2d R = T.rotation();
  const Point2 translation = T.translation();
  const double max_distance = config.max_correspondence_distance;
  const double max_length = config.max_segment_length;
  const bool doubles = kReject && config.outliers_remove_doubles;
  // Raw pointers held in locals: Eigen's packet stores may alias anything, and would otherwise
  // make every vector's data pointer be reloaded after each store into a pair.
  const Point2* const sources = source.points.data();
  const Point2* const targets = t.points.data();
  const double* const segment_lengths = t.segment_lengths.data();
  const Point2* const segment_normals = t.segment_normals.data();
  double* const closest = ws.closest.data();
  SourcePair* const pairs = ws.pairs.data();
  const int target_count = t.size();
  if (doubles) std::fill(closest, closest + target_count, kInfinity);
  int previous = kNone;  // the last j1 found: where a fresh walk starts (the source is a scan too)
  const std::size_t count = ws.pairs.size();
  for (std::size_t i = 0; i < count; ++i) {
    SourcePair& s = pairs[i];
    const Point2 moved = R * sources[i] + translation;  // Eq. (1)
    const int j1 = track_nearest(t, moved, max_distance, s.nearest, previous);
    s.moved = moved;
    s.j1 = j1;
    s.j2 = kNone;
    if (j1 == kNone) continue;
    previous = j1;
    if (target_count < 2) continue;  // a one-point target has no segment
    // j2: the closer of j1's scan neighbours (ties: the one below), chosen without a branch.
    const double below = j1 > 0 ? (targets[j1 - 1] - moved).squaredNorm() : kInfinity;
    const double above = j1 + 1 < target_count ? (targets[j1 + 1] - moved).squaredNorm() : kInfinity;
    const int j2 = j1 + 1 - 2 * static_cast<int>(below <= above);
    const int segment = std::min(j1, j2);
    if (kReject && segment_lengths[segment] > max_length) continue;  // dropped: too long
    const Point2 normal = segment_normals[segment];
    const Point2 offset = moved - targets[j1];
    const double distance = std::abs(normal.dot(offset));  // to the line, the metric of Eq. (4)
    // To the segment: beyond either end, to that end (the projection's parameter on j1 -> j2, clamped).
    const Point2 along = targets[j2] - targets[j1];
    const double u = std::clamp(offset.dot(along) / std::max(along.squaredNorm(), 1e-300), 0.0, 1.0);
    s.j2 = j2;
    s.normal = normal;
    s.distance = distance;
    s.segment_distance = (offset - u * along).norm();
    s.point_distance = offset.norm();
    if (doubles) closest[j1] = std::min(closest[j1], s.point_distance);
  }
}

// j2, or kNone (-1, all bits set) unless keep: without a branch, which compilers tend to make
// of a conditional store, and which the data-dependent rejections mispredict.
inline int unpair_unless(bool keep, int j2) {
  static_assert(kNone == -1);
  return j2 | (static_cast<int>(keep) - 1);
}

// CSM's kill_outliers_double: of the source points sharing a j1, drops those more than
// kDoublesRatio times as far from p_j1 as the closest one. (Keeping the closest alone, or choosing
// by the distance to the line, keeps the pairs that agree best with the current estimate: the
// iteration then stops where it already is, with part of the guess's rotation error.)
constexpr double kDoublesRatio = 3.0;

// The doubles; collects the segment distances of the pairs kept into ws.distances and returns
// their count (the long segments went in find_correspondences<true>).
std::size_t drop_doubles(const PlIcpConfig& config, Workspace& ws) {
  double* const out = ws.distances.data();
  const double* const closest = ws.closest.data();
  const bool doubles = config.outliers_remove_doubles;
  std::size_t kept = 0;
  for (SourcePair& s : ws.pairs) {  // without a branch: which pairs go is data-dependent
    const bool keep = s.paired() & !(doubles & (s.point_distance > kDoublesRatio * closest[std::max(s.j1, 0)]));
    s.j2 = unpair_unless(keep, s.j2);
    out[kept] = s.segment_distance;
    kept += keep;
  }
  return kept;
}

// Eq. (3): min(e_(maxPerc), mult * e_(order)), e_(f) the value at fraction f of the sorted
// distances (CSM's hoare_selection at floor(n f)); n > 0 distances in ws.distances.
double trimming_limit(const PlIcpConfig& config, std::size_t n, Workspace& ws) {
  const auto rank = [n](double fraction) { return std::min(n - 1, static_cast<std::size_t>(fraction * static_cast<double>(n))); };
  const std::size_t trimmed = rank(config.outliers_max_fraction);
  const std::size_t adaptive = rank(config.outliers_adaptive_order);
  const BucketSelector selector(config.max_correspondence_distance);
  const auto [lower, upper] = selector.ranks(ws.distances.data(), n, std::min(trimmed, adaptive),
                                             std::max(trimmed, adaptive), ws.distance_buckets, ws.selection_scratch);
  const double trimmed_value = adaptive <= trimmed ? upper : lower;
  const double adaptive_value = adaptive <= trimmed ? lower : upper;
  return std::min(trimmed_value, config.outliers_adaptive_mult * adaptive_value);
}

// The pairs kept, and a hash of the association (j1, j2 per source point): when an association
// comes back, the estimate it gives comes back too, so the loop has reached a fixed point or a
// cycle (CSM's loop detection).
struct Association {
  std::size_t kept = 0;
  std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a
};

// Eq. (3) and the other rejections: long segments, doubles, trimming. Lists the kept pairs'
// source points in ws.inliers.
Association reject_outliers(const PlIcpConfig& config, Workspace& ws) {
  ws.inlier_count = 0;
  const std::size_t kept = drop_doubles(config, ws);
  Association association;
  if (kept == 0) return association;
  const double limit = trimming_limit(config, kept, ws);
  int* const inliers = ws.inliers.data();
  const int count = static_cast<int>(ws.pairs.size());
  for (int i = 0; i < count; ++i) {  // without a branch, as in drop_doubles
    SourcePair& s = ws.pairs[i];
    const bool keep = s.paired() & !(s.segment_distance > limit);
    s.j2 = unpair_unless(keep, s.j2);
    const std::uint64_t pair = (static_cast<std::uint64_t>(s.j1) << 32) ^ static_cast<std::uint32_t>(s.j2);
    const std::uint64_t dropped = static_cast<std::uint64_t>(keep) - 1;  // all bits set, or none when kept
    association.hash = (association.hash ^ (pair | dropped)) * 1099511628211ULL;
    inliers[association.kept] = i;
    association.kept += keep;
  }
  ws.inlier_count = association.kept;
  return association;
}

double weight(const PointCloud2& source, std::size_t i) { return source.has_weights() ? source.weights[i] : 1.0; }

// Eq. (4): the sum of add_term over the pairs, with the upper triangle of M in scalars and g
// gathered as sum w a b (times -2 at the end).
template <bool kWeighted>
PointToLineProblem build_problem(const TargetIndex& t, const PointCloud2& source, const Workspace& ws) {
  double m00 = 0, m01 = 0, m02 = 0, m03 = 0, m11 = 0, m12 = 0, m13 = 0, m22 = 0, m23 = 0, m33 = 0;
  double g0 = 0, g1 = 0, g2 = 0, g3 = 0, c = 0;
  for (std::size_t k = 0; k < ws.inlier_count; ++k) {
    const int i = ws.inliers[k];
    const SourcePair& s = ws.pairs[i];
    const double nx = s.normal.x(), ny = s.normal.y(), px = s.moved.x(), py = s.moved.y();
    // a = (n_x, n_y, n^T p, n^T J p), b = n^T q (add_term).
    const double a2 = nx * px + ny * py, a3 = ny * px - nx * py;
    const Point2& q = t.points[s.j1];
    const double b = nx * q.x() + ny * q.y();
    double w0 = nx, w1 = ny, w2 = a2, w3 = a3, wb = b;
    if constexpr (kWeighted) {
      const double w = source.weights[i];
      w0 *= w, w1 *= w, w2 *= w, w3 *= w, wb *= w;
    }
    m00 += w0 * nx, m01 += w0 * ny, m02 += w0 * a2, m03 += w0 * a3;
    m11 += w1 * ny, m12 += w1 * a2, m13 += w1 * a3;
    m22 += w2 * a2, m23 += w2 * a3, m33 += w3 * a3;
    g0 += w0 * b, g1 += w1 * b, g2 += w2 * b, g3 += w3 * b;
    c += wb * b;
  }
  PointToLineProblem problem;
  problem.M << m00, m01, m02, m03, m01, m11, m12, m13, m02, m12, m22, m23, m03, m13, m23, m33;
  problem.g << -2.0 * g0, -2.0 * g1, -2.0 * g2, -2.0 * g3;
  problem.c = c;
  problem.terms = ws.inlier_count;
  return problem;
}

PointToLineProblem build_problem(const TargetIndex& t, const PointCloud2& source, const Workspace& ws) {
  return source.has_weights() ? build_problem<true>(t, source, ws) : build_problem<false>(t, source, ws);
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
                                     Workspace& ws, double range_sigma) {
  const Eigen::Matrix2d R = T.rotation();
  SymmetricSum3 hessian, spread_sum;
  double curvature = 0.0;  // the e da/dx part of H(2, 2)
  // Raw pointers in locals: the column updates are Eigen packet stores, which may alias anything.
  Eigen::Vector3d* const target_columns = ws.target_columns.data();
  std::fill(target_columns, target_columns + t.size(), Eigen::Vector3d::Zero());
  const SourcePair* const source_pairs = ws.pairs.data();
  const Point2* const sources = source.points.data();
  const Point2* const targets = t.points.data();
  const Point2* const directions = t.directions.data();
  const double* const segment_lengths = t.segment_lengths.data();
  const int* const inliers = ws.inliers.data();
  const std::size_t pairs = ws.inlier_count;
  const double tx = T.x(), ty = T.y(), c = R(0, 0), sn = R(1, 0);
  for (std::size_t k = 0; k < pairs; ++k) {
    const int i = inliers[k];
    const SourcePair& s = source_pairs[i];
    // The segment (q1, q2) from the target's tables: n = J d / |d| is its stored normal, turned
    // when q2 comes before q1 in the scan.
    const int segment = std::min(s.j1, s.j2);
    const double length = segment_lengths[segment];
    if (!(length > 1e-12)) continue;
    const double inverse_length = 1.0 / length;
    const double turn = s.j2 > s.j1 ? 1.0 : -1.0;
    const double nx = turn * s.normal.x(), ny = turn * s.normal.y();  // along = d / |d| = (ny, -nx)
    const Point2& q1 = targets[s.j1];
    const Point2& p = sources[i];
    const double rpx = c * p.x() - sn * p.y(), rpy = sn * p.x() + c * p.y();  // R p; d(R p)/d theta = (-rpy, rpx)
    const double ox = rpx + tx - q1.x(), oy = rpy + ty - q1.y();            // offset = R p + t - q1
    const double e = nx * ox + ny * oy;
    const double w2 = 2.0 * weight(source, i);
    const double a2 = ny * rpx - nx * rpy;      // n^T d(R p)/d theta
    const double n_rp = nx * rpx + ny * rpy;    // n^T R p
    const double along_offset = ny * ox - nx * oy;  // along^T offset
    hessian.add(Eigen::Vector3d(nx, ny, a2), w2);
    curvature -= w2 * e * n_rp;
    // d2J/dz dx = w2 (de/dz a + e (dn/dz, dn/dz^T d(R p)/d theta)), a = (nx, ny, a2).
    const auto column = [&](double de, double dnx, double dny) -> Eigen::Vector3d {
      return Eigen::Vector3d(w2 * (de * nx + e * dnx), w2 * (de * ny + e * dny),
                             w2 * (de * a2 + e * (dny * rpx - dnx * rpy)));
    };
    // The source range moves p along its bearing u: de = n^T R u, and n^T J R u for the angle.
    const double range = p.norm();
    const double inverse_range = range > 1e-12 ? 1.0 / range : 0.0;
    const double de = n_rp * inverse_range;
    const double dn_theta = a2 * inverse_range;
    spread_sum.add(Eigen::Vector3d(w2 * de * nx, w2 * de * ny, w2 * (de * a2 + e * dn_theta)));
    // The target ranges move q1 and q2 along their bearings u1, u2: dn = -+(n^T dq / |d|) along.
    const double beta1 = (nx * directions[s.j1].x() + ny * directions[s.j1].y()) * inverse_length;
    target_columns[s.j1] += column(beta1 * length * (along_offset * inverse_length - 1.0), beta1 * ny, -beta1 * nx);
    const double beta2 = (nx * directions[s.j2].x() + ny * directions[s.j2].y()) * inverse_length;
    target_columns[s.j2] += column(-beta2 * along_offset, -beta2 * ny, beta2 * nx);
  }
  Eigen::Matrix3d H = hessian.matrix();
  H(2, 2) += curvature;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
  const double scale = H.diagonal().cwiseAbs().maxCoeff();
  if (pairs < 3 || ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(scale > 0.0) ||
      ldlt.vectorD().minCoeff() <= 1e-12 * scale) {
    return unknown_covariance();
  }
  const Eigen::Matrix3d H_inverse = ldlt.solve(Eigen::Matrix3d::Identity());
  for (int k = 0; k < t.size(); ++k) spread_sum.add(target_columns[k]);
  const Eigen::Matrix3d spread = spread_sum.matrix() * (range_sigma * range_sigma);
  const Covariance3 covariance = H_inverse * spread * H_inverse;
  if (!covariance.allFinite()) return unknown_covariance();
  return make_positive_definite(0.5 * (covariance + covariance.transpose()), 1e-18);
}

// The unit normal of the total least squares line through target point k and up to
// kNormalHalfWindow neighbours on either side (stopping at gaps longer than max_gap), for the
// Fisher information: a two-point segment's normal is too noisy near the sensor to tell a
// corridor from a room. Closed form: the eigenvector of the scatter's smaller eigenvalue, the
// scatter from the prefix sums `moments` of the target points (moments[k] sums points [0, k); in
// absolute coordinates: with ranges of tens of metres the scatter keeps about 1e-11 m^2, the
// normal's direction 1e-9 rad). ws holds the prefix sums and the runs (prepare_fitted_normals).
constexpr int kNormalHalfWindow = 3;

void prepare_fitted_normals(const TargetIndex& t, double max_gap, Workspace& ws) {
  const int n = t.size();
  ws.target_moments[0] = {};
  for (int k = 0; k < n; ++k) ws.target_moments[k + 1] = ws.target_moments[k].plus(t.points[k]);
  ws.run_first[0] = 0;
  for (int k = 1; k < n; ++k) ws.run_first[k] = t.segment_lengths[k - 1] <= max_gap ? ws.run_first[k - 1] : k;
  ws.run_last[n - 1] = n - 1;
  for (int k = n - 2; k >= 0; --k) ws.run_last[k] = t.segment_lengths[k] <= max_gap ? ws.run_last[k + 1] : k;
}

Point2 fitted_normal(const Workspace& ws, int k) {
  const int lo = std::max(k - kNormalHalfWindow, ws.run_first[k]);
  const int hi = std::min(k + kNormalHalfWindow, ws.run_last[k]);
  if (hi - lo < 2) return Point2::Zero();
  const std::vector<PointMoments>& moments = ws.target_moments;
  const PointMoments sum = moments[hi + 1].minus(moments[lo]);
  const double inverse_count = 1.0 / static_cast<double>(hi - lo + 1);
  const double sxx = sum.xx - sum.x * sum.x * inverse_count;
  const double sxy = sum.xy - sum.x * sum.y * inverse_count;
  const double syy = sum.yy - sum.y * sum.y * inverse_count;
  const double smallest = 0.5 * (sxx + syy) - std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
  const Point2 a(sxy, smallest - sxx), b(smallest - syy, sxy);
  const Point2 normal = a.squaredNorm() >= b.squaredNorm() ? a : b;
  return normal.squaredNorm() > 0.0 ? Point2(normal.normalized()) : Point2::Zero();
}

// Degeneracy (degeneracy.hpp) from the final pairs, with fitted normals at their j1: the Fisher
// information that analyze_degeneracy sums for these pairs, here without copying the target.
DegeneracyAnalysis pl_icp_degeneracy(const PointCloud2& source, const SE2& T, const TargetIndex& t,
                                     Workspace& ws, const PlIcpConfig& config) {
  const DegeneracyConfig degeneracy{.range_sigma = config.range_sigma};
  const double inverse_variance = 1.0 / (config.range_sigma * config.range_sigma);
  const Eigen::Matrix2d R = T.rotation();
  SymmetricSum3 information_sum;
  double squared_radius_sum = 0.0;
  std::size_t used = 0;
  prepare_fitted_normals(t, config.max_segment_length, ws);
  for (std::size_t k = 0; k < ws.inlier_count; ++k) {
    const int i = ws.inliers[k];
    const SourcePair& s = ws.pairs[i];
    const Point2 n = fitted_normal(ws, s.j1);
    if (!(n.squaredNorm() > 0.5)) continue;  // no fitted normal (has_normal)
    const Point2 Rp = R * source.points[i];
    const Eigen::Vector3d a(n.x(), n.y(), n.dot(Point2(-Rp.y(), Rp.x())));
    information_sum.add(a, inverse_variance);
    squared_radius_sum += source.points[i].squaredNorm();
    ++used;
  }
  const Eigen::Matrix3d information = information_sum.matrix();
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
  for (std::size_t k = 0; k < ws.inlier_count; ++k) {
    const int i = ws.inliers[k];
    const SourcePair& s = ws.pairs[i];
    const double w = weight(source, i);
    sum += w * s.distance * s.distance;
    weights += w;
  }
  return weights > 0.0 ? std::sqrt(sum / weights) : 0.0;
}

// Moves the source points of the kept pairs to T and measures their distances to their lines
// again, keeping the association.
void move_pairs(const TargetIndex& t, const PointCloud2& source, const SE2& T, Workspace& ws) {
  const Eigen::Matrix2d R = T.rotation();
  for (std::size_t k = 0; k < ws.inlier_count; ++k) {
    const int i = ws.inliers[k];
    SourcePair& s = ws.pairs[i];
    s.moved = R * source.points[i] + T.translation();
    s.distance = std::abs(s.normal.dot(s.moved - t.points[s.j1]));
  }
}

// The result at the estimate T: its covariance (Censi 2007), RMS residual and degeneracy, from
// the last association (CSM's too): the one found at T itself when the loop stopped on a repeated
// association, else the one that gave the last step, with the points moved to T.
MatchResult finish(const PointCloud2& source, const TargetIndex& t, const SE2& T, bool converged,
                   bool associated_at_T, int iterations, const PlIcpConfig& config, Workspace& ws) {
  if (!associated_at_T) move_pairs(t, source, T, ws);
  const std::size_t inliers = ws.inlier_count;
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
  check_fields(config, "PlIcpConfig");
}

std::vector<Correspondence> pl_icp_correspondences(const PointCloud2& target, const PointCloud2& source,
                                                   const SE2& T_target_source, const PlIcpConfig& config) {
  validate(config);
  const TargetIndex t = prepare_target(target, config.search);
  std::vector<Correspondence> pairs;
  if (t.size() == 0) return pairs;
  Workspace ws(source.size(), t.points.size());
  find_correspondences<false>(t, source, T_target_source, config, ws);
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
  // Per thread, reused from match to match: the buffers are allocated once (a few kB).
  thread_local TargetIndex t;
  thread_local Workspace ws;
  thread_local std::vector<std::uint64_t> associations;
  // Successive matches against one target (a keyframe, a local map) prepare it once.
  thread_local std::vector<Point2> prepared_points;
  thread_local std::optional<PlIcpSearch> prepared_search;
  if (prepared_search != config.search || prepared_points != target.points) {
    prepare_target(target, config.search, t);
    prepared_points = target.points;
    prepared_search = config.search;
  }
  if (t.size() < 3 || source.size() < 3) {  // nothing to match: the guess, unconverged, huge covariance
    MatchResult result;
    result.T_target_source = T_target_source_guess;
    apply(analyze_degeneracy(target, source, T_target_source_guess, {}), result);
    return result;
  }
  ws.reset(source.size(), t.points.size());
  SE2 T = T_target_source_guess;
  bool converged = false;
  bool associated_at_T = false;
  int iteration = 0;
  associations.clear();
  while (iteration < config.max_iterations && !converged) {
    ++iteration;
    find_correspondences<true>(t, source, T, config, ws);                                       // Eq. (1)-(3)
    const Association association = reject_outliers(config, ws);                                // Eq. (3)
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
