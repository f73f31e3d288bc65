// SPDX-License-Identifier: BSD-3-Clause
// IMRP and IDC (F. Lu and E. Milios, J. Intelligent and Robotic Systems 18, 1997, Sec. 4).
// Equation numbers refer to idc.hpp.

#include "slam2d/registration/idc.hpp"

#include <algorithm>
#include <Eigen/Cholesky>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/registration/degeneracy.hpp"
#include "slam2d/registration/nearest_association.hpp"
#include "slam2d/registration/normals.hpp"

namespace slam2d {
namespace {

constexpr double kPi = std::numbers::pi;

// ---- Configuration ----

// Eq. (6): an exponentially shrinking bound with a floor.
double shrinking(double initial, double final_value, double decay, int iteration) {
  return std::max(final_value, initial * std::exp(-decay * iteration));
}

// The stopping test: the step is below the tolerances, or, once the bounds of Eq. (6) have
// reached their floors, the iteration came back to a pose of the last two (the correspondences
// alternate between two sets): PoseCycle with a period of two.
bool converged(const SE2& before, const SE2& after, double translation_tolerance, double rotation_tolerance,
               bool settled, PoseCycle& cycle) {
  const bool returned = cycle.returned_to(after, translation_tolerance, rotation_tolerance);
  return step_below(before, after, translation_tolerance, rotation_tolerance) || (settled && returned);
}

// ---- The two rules' point pairs ----

struct PointPairs {
  std::vector<Point2> moved;    // T p, target frame
  std::vector<Point2> target;   // their partners on the target polyline
  std::vector<Point2> normals;  // range rule: unit normal of the partner's segment (zero: an isolated point)
  std::size_t size() const { return moved.size(); }
};

PointPairs closest_point_pairs(const ScanPolyline& target, const PointCloud2& source, const SE2& T,
                               double max_distance) {
  PointPairs pairs;
  pairs.moved.reserve(source.size());
  pairs.target.reserve(source.size());
  for (const Point2& p : source.points) {
    const Point2 m = T * p;
    if (const auto q = closest_point(target, m, max_distance)) {  // Eq. (1)
      pairs.moved.push_back(m);
      pairs.target.push_back(q->point);
    }
  }
  return pairs;
}

Point2 segment_normal(const ScanPolyline& polyline, std::size_t k) {
  if (k + 1 >= polyline.points.size() || !polyline.connected[k]) return Point2::Zero();
  const Point2 d = polyline.points[k + 1] - polyline.points[k];
  const double length = d.norm();
  return length > 1e-12 ? Point2(-d.y() / length, d.x() / length) : Point2::Zero();
}

PointPairs matching_range_pairs(const ScanPolyline& target, const PointCloud2& source, const SE2& T, double window,
                                double max_range_difference) {
  const auto matches = matching_range_points(target, source, T, window, max_range_difference);  // Eq. (2)
  PointPairs pairs;
  pairs.moved.reserve(source.size());
  pairs.target.reserve(source.size());
  pairs.normals.reserve(source.size());
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (!matches[i]) continue;
    pairs.moved.push_back(T * source.points[i]);
    pairs.target.push_back(matches[i]->point);
    pairs.normals.push_back(segment_normal(target, matches[i]->segment));
  }
  return pairs;
}

Point2 mean_of(const std::vector<Point2>& points) {
  Point2 sum = Point2::Zero();
  for (const Point2& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

// Eq. (3'): the motion D about the source sensor o (small-angle linearisation) that minimises
// the range rule's pairs' distances measured along their target segments' normals,
//   min sum (n_i^T (D m_i - q_i))^2,  D m = R(w) (m - o) + o + t,
// one Gauss-Newton step. The pairs' own displacement q_i - m_i runs across the beam, so the
// point-to-point closed form (Eq. (3)-(4)) would also assert "no radial motion" at every pair
// and pull the translation back (see docs/methods/idc.md); along the normal the pair carries
// exactly the information it has. Isolated target points (no segment) are left out.
std::optional<SE2> range_rule_motion(const PointPairs& range, const Point2& o, std::size_t min_pairs) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  std::size_t used = 0;
  for (std::size_t i = 0; i < range.size(); ++i) {
    const Point2& n = range.normals[i];
    if (n.squaredNorm() == 0.0) continue;
    const Point2 r = range.moved[i] - o;
    const Eigen::Vector3d a(n.x(), n.y(), n.dot(Point2(-r.y(), r.x())));  // d(n^T D m)/d(t, w)
    H += a * a.transpose();
    g += a * n.dot(range.moved[i] - range.target[i]);
    ++used;
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
  if (used < min_pairs || ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      !(ldlt.vectorD().minCoeff() > 1e-12 * H.trace())) {
    return std::nullopt;
  }
  const Eigen::Vector3d delta = -ldlt.solve(g);
  return SE2(o, 0.0) * SE2(delta.head<2>(), delta.z()) * SE2(-o, 0.0);
}

// Eq. (4) with a given rotation w: the least-squares translation of the pairs.
SE2 motion_given_rotation(const PointPairs& pairs, double w) {
  const Point2 a_mean = mean_of(pairs.moved);
  const Point2 b_mean = mean_of(pairs.target);
  return SE2(b_mean - SE2(0.0, 0.0, w).rotation() * a_mean, w);
}

// ---- Polyline search ----

// atan2 within about 1e-5 rad, several times faster than std::atan2: for search starts and bins.
double fast_atan2(double y, double x) {
  const double ax = std::abs(x);
  const double ay = std::abs(y);
  const double hi = std::max(ax, ay);
  if (hi == 0.0) return 0.0;
  const double a = std::min(ax, ay) / hi;
  const double s = a * a;
  double r = (((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s) * a + a;  // atan(a), a in [0, 1]
  if (ay > ax) r = kPi / 2.0 - r;
  if (x < 0.0) r = kPi - r;
  return y < 0.0 ? -r : r;
}

double cross(const Point2& a, const Point2& b) { return a.x() * b.y() - a.y() * b.x(); }

// The best candidate so far of the closest-point rule, as a squared distance.
struct ClosestCandidate {
  PolylinePoint point;
  double squared = 0.0;
  bool found = false;
};

void consider_vertex(const ScanPolyline& polyline, std::size_t k, const Point2& m, ClosestCandidate& best) {
  const double squared = (polyline.points[k] - m).squaredNorm();
  if (squared >= best.squared) return;
  best = {PolylinePoint{.segment = k, .s = 0.0, .point = polyline.points[k]}, squared, true};
}

void consider_segment(const ScanPolyline& polyline, std::size_t k, const Point2& m, ClosestCandidate& best) {
  if (k + 1 >= polyline.points.size() || !polyline.connected[k]) return;
  const Point2& a = polyline.points[k];
  const Point2 d = polyline.points[k + 1] - a;
  const double length_squared = d.squaredNorm();
  const double s = length_squared > 0.0 ? std::clamp((m - a).dot(d) / length_squared, 0.0, 1.0) : 0.0;
  const Point2 foot = a + s * d;
  const double squared = (foot - m).squaredNorm();
  if (squared >= best.squared) return;
  best = {PolylinePoint{.segment = k, .s = s, .point = foot}, squared, true};
}

// The query's bearing, unwrapped next to the polyline's bearing interval [b_0, b_0 + 2 pi).
double unwrapped_bearing(const ScanPolyline& polyline, const Point2& m) {
  const double first = polyline.bearings.front();
  double offset = fast_atan2(m.y(), m.x()) - first;  // in (-3 pi, pi]
  while (offset < 0.0) offset += 2.0 * kPi;
  double beta = first + offset;
  const double past_end = beta - polyline.bearings.back();
  if (past_end > 0.0 && first + 2.0 * kPi - beta < past_end) beta -= 2.0 * kPi;
  return beta;
}

// Walks the ordered polyline from `start` in `direction` (+1, -1), wrapping around with the
// bearing shifted by 2 pi, until no farther point can beat the best: a point whose bearing differs
// by delta from the query's (range rho) is at least rho sin(delta) away (rho when delta >= pi/2).
void walk(const ScanPolyline& polyline, const Point2& m, double rho, double beta, std::ptrdiff_t start, int direction,
          ClosestCandidate& best) {
  const Point2 u = m / rho;
  const auto n = static_cast<std::ptrdiff_t>(polyline.points.size());
  for (std::ptrdiff_t step = 0; step < n; ++step) {
    const std::ptrdiff_t j = start + direction * step;
    const std::ptrdiff_t wraps = j >= 0 ? j / n : -((-j + n - 1) / n);
    const auto k = static_cast<std::size_t>(j - wraps * n);
    if (direction < 0) consider_segment(polyline, k, m, best);  // joins k to the point visited before
    const double delta = std::abs(polyline.bearings[k] + 2.0 * kPi * static_cast<double>(wraps) - beta);
    const double bound = delta >= kPi / 2.0 ? rho : rho * std::abs(cross(polyline.directions[k], u));  // rho sin(delta)
    if (bound * bound >= best.squared) return;
    consider_vertex(polyline, k, m, best);
    if (direction > 0) consider_segment(polyline, k, m, best);
  }
}

std::optional<PolylinePoint> closest_point_linear(const ScanPolyline& polyline, const Point2& query,
                                                  double max_distance) {
  ClosestCandidate best;
  best.squared = max_distance * max_distance;
  for (std::size_t k = 0; k < polyline.points.size(); ++k) {
    consider_vertex(polyline, k, query, best);
    consider_segment(polyline, k, query, best);
  }
  if (!best.found) return std::nullopt;
  best.point.distance = std::sqrt(best.squared);
  return best.point;
}

}  // namespace

ScanPolyline make_scan_polyline(const PointCloud2& cloud, double max_gap) {
  ScanPolyline polyline;
  polyline.points = cloud.points;
  const std::size_t n = cloud.size();
  polyline.connected.assign(n > 0 ? n - 1 : 0, 0);
  polyline.bearings.resize(n);
  polyline.directions.resize(n, Point2::Zero());
  const double max_gap_squared = max_gap * max_gap;
  for (std::size_t k = 0; k < n; ++k) {
    const Point2& p = cloud.points[k];
    const double bearing = std::atan2(p.y(), p.x());
    polyline.directions[k] = Point2(std::cos(bearing), std::sin(bearing));
    if (k == 0) {
      polyline.bearings[k] = bearing;
      continue;
    }
    const double step = angle_difference(bearing, std::atan2(cloud.points[k - 1].y(), cloud.points[k - 1].x()));
    polyline.bearings[k] = polyline.bearings[k - 1] + step;
    polyline.ordered = polyline.ordered && step > 0.0;
    polyline.connected[k - 1] = (p - cloud.points[k - 1]).squaredNorm() <= max_gap_squared ? 1 : 0;
  }
  polyline.ordered = polyline.ordered && n > 0 && polyline.bearings.back() - polyline.bearings.front() < 2.0 * kPi;
  return polyline;
}

std::optional<PolylinePoint> closest_point(const ScanPolyline& polyline, const Point2& query, double max_distance) {
  if (polyline.points.empty() || !(max_distance > 0.0)) return std::nullopt;
  ClosestCandidate best;
  best.squared = max_distance * max_distance;
  if (polyline.ordered) {
    const double beta = unwrapped_bearing(polyline, query);
    const auto start = static_cast<std::ptrdiff_t>(
        std::lower_bound(polyline.bearings.begin(), polyline.bearings.end(), beta) - polyline.bearings.begin());
    const double rho = query.norm();
    if (!(rho > 0.0)) return closest_point_linear(polyline, query, max_distance);
    walk(polyline, query, rho, beta, start, +1, best);
    walk(polyline, query, rho, beta, start - 1, -1, best);
  } else {
    return closest_point_linear(polyline, query, max_distance);
  }
  if (!best.found) return std::nullopt;
  best.point.distance = std::sqrt(best.squared);
  return best.point;
}

// ---- The matching-range-point rule's search ----

namespace {

constexpr int kBearingBins = 256;
constexpr double kBinWidth = 2.0 * kPi / kBearingBins;  // rad
constexpr double kBinPadding = 1e-4;                    // rad, covers fast_atan2's error
constexpr double kTie = 1e-9;                           // m, range differences this close are equal

int bearing_bin(double bearing) {
  const int bin = static_cast<int>(std::floor((bearing + kPi) / kBinWidth)) % kBearingBins;
  return bin < 0 ? bin + kBearingBins : bin;
}

// A piece of the target polyline: the segment from point a to point b (a == b: an isolated point).
struct Piece {
  std::uint32_t a = 0;
  std::uint32_t b = 0;
};

// The polyline's pieces filed by the bearings they cover as seen from the source sensor o.
struct BearingBins {
  std::vector<Point2> relative;          // q_k - o
  std::vector<Piece> pieces;
  std::vector<std::uint32_t> offsets;    // bin j holds ids[offsets[j] .. offsets[j + 1])
  std::vector<std::uint32_t> ids;        // piece ids
  std::vector<double> range_low;         // m, per piece: the least range from o
  std::vector<double> range_high;        // m, the greatest
};

// The range span of each piece seen from o (origin of `relative`).
void piece_ranges(BearingBins& bins) {
  bins.range_low.resize(bins.pieces.size());
  bins.range_high.resize(bins.pieces.size());
  for (std::size_t id = 0; id < bins.pieces.size(); ++id) {
    const Point2& a = bins.relative[bins.pieces[id].a];
    const Point2& b = bins.relative[bins.pieces[id].b];
    const Point2 d = b - a;
    const double dd = d.squaredNorm();
    const double s = dd > 0.0 ? std::clamp(-a.dot(d) / dd, 0.0, 1.0) : 0.0;
    bins.range_low[id] = (a + s * d).norm();
    bins.range_high[id] = std::sqrt(std::max(a.squaredNorm(), b.squaredNorm()));
  }
}

std::vector<Piece> polyline_pieces(const ScanPolyline& target) {
  std::vector<Piece> pieces;
  const std::size_t n = target.points.size();
  for (std::size_t k = 0; k < n; ++k) {
    const bool after = k + 1 < n && target.connected[k];
    const bool before = k > 0 && target.connected[k - 1];
    const auto a = static_cast<std::uint32_t>(k);
    if (after) pieces.push_back({a, a + 1});
    if (!after && !before) pieces.push_back({a, a});
  }
  return pieces;
}

BearingBins bin_pieces(const ScanPolyline& target, const Point2& origin) {
  BearingBins bins;
  bins.pieces = polyline_pieces(target);
  bins.relative.reserve(target.points.size());
  std::vector<double> bearing;
  bearing.reserve(target.points.size());
  for (const Point2& q : target.points) {
    bins.relative.push_back(q - origin);
    bearing.push_back(fast_atan2(bins.relative.back().y(), bins.relative.back().x()));
  }
  std::vector<int> first(bins.pieces.size());
  std::vector<int> count(bins.pieces.size());
  bins.offsets.assign(kBearingBins + 1, 0);
  for (std::size_t id = 0; id < bins.pieces.size(); ++id) {
    const Piece& piece = bins.pieces[id];
    const double span = angle_difference(bearing[piece.b], bearing[piece.a]);
    const double low = span >= 0.0 ? bearing[piece.a] : bearing[piece.b];
    first[id] = bearing_bin(low - kBinPadding);
    count[id] = (bearing_bin(low + std::abs(span) + kBinPadding) - first[id] + kBearingBins) % kBearingBins + 1;
    for (int j = 0; j < count[id]; ++j) ++bins.offsets[(first[id] + j) % kBearingBins + 1];
  }
  for (int j = 0; j < kBearingBins; ++j) bins.offsets[j + 1] += bins.offsets[j];
  bins.ids.resize(bins.offsets.back());
  std::vector<std::uint32_t> fill(bins.offsets.begin(), bins.offsets.end() - 1);
  for (std::size_t id = 0; id < bins.pieces.size(); ++id) {
    for (int j = 0; j < count[id]; ++j) bins.ids[fill[(first[id] + j) % kBearingBins]++] = static_cast<std::uint32_t>(id);
  }
  piece_ranges(bins);
  return bins;
}

// The best point of the range rule so far, in the query's frame (x along its bearing).
struct RangeCandidate {
  double difference = std::numeric_limits<double>::infinity();  // m, | |q - o| - r |
  double tan_bearing = std::numeric_limits<double>::infinity();  // |tan| of the bearing difference
  Piece piece;
  double s = 0.0;
  Point2 local = Point2::Zero();
};

// Offers the point at s of the piece (local coordinates a + s d) to the rule, Eq. (2), with its
// range difference (0 for a crossing of the radius r).
void offer(const Point2& a, const Point2& d, double s, double difference, const Piece& piece, RangeCandidate& best) {
  const Point2 x = a + s * d;
  if (!(x.x() > 0.0)) return;
  const double tan_bearing = std::abs(x.y()) / x.x();
  if (difference < best.difference - kTie || (difference <= best.difference + kTie && tan_bearing < best.tan_bearing)) {
    best = {difference, tan_bearing, piece, s, x};
  }
}

void offer_inexact(const Point2& a, const Point2& d, double s, double r, const Piece& piece, RangeCandidate& best) {
  offer(a, d, s, std::abs((a + s * d).norm() - r), piece, best);
}

// Clips [low, high] to where g(s) = g0 + s (g1 - g0) <= 0.
void clip(double g0, double g1, double& low, double& high) {
  if (g0 <= 0.0 && g1 <= 0.0) return;
  if (g0 > 0.0 && g1 > 0.0) {
    high = -1.0;
    return;
  }
  const double root = g0 / (g0 - g1);
  if (g0 > 0.0) low = std::max(low, root);
  else high = std::min(high, root);
}

// The piece's part inside the window |bearing| <= B (|y| <= x tan B, linear in s), then the
// points of that part whose range comes closest to r: the crossings of the radius r when there
// are any, else (the range being convex along a segment) the ends or the foot of the
// perpendicular from o. Once some piece crosses r, pieces whose range span misses r cannot win.
void test_piece(const BearingBins& bins, std::uint32_t id, const Point2& u, double r, double tan_window,
                RangeCandidate& best) {
  const bool exact_found = best.difference <= kTie;
  if (exact_found && (r < bins.range_low[id] || r > bins.range_high[id])) return;
  const Piece& piece = bins.pieces[id];
  const Point2& qa = bins.relative[piece.a];
  const Point2& qb = bins.relative[piece.b];
  const Point2 a(u.dot(qa), cross(u, qa));
  const Point2 d = Point2(u.dot(qb), cross(u, qb)) - a;
  double low = 0.0;
  double high = 1.0;
  clip(a.y() - tan_window * a.x(), (a.y() + d.y()) - tan_window * (a.x() + d.x()), low, high);
  clip(-a.y() - tan_window * a.x(), -(a.y() + d.y()) - tan_window * (a.x() + d.x()), low, high);
  if (low > high) return;
  const double dd = d.squaredNorm();
  if (dd <= 0.0) {
    offer_inexact(a, d, 0.0, r, piece, best);
    return;
  }
  const double ad = a.dot(d);
  const double discriminant = ad * ad - dd * (a.squaredNorm() - r * r);
  if (discriminant >= 0.0) {
    for (const double root : {(-ad - std::sqrt(discriminant)) / dd, (-ad + std::sqrt(discriminant)) / dd}) {
      if (root >= low && root <= high) offer(a, d, root, 0.0, piece, best);
    }
  }
  if (best.difference <= kTie) return;
  offer_inexact(a, d, low, r, piece, best);
  offer_inexact(a, d, high, r, piece, best);
  offer_inexact(a, d, std::clamp(-ad / dd, low, high), r, piece, best);
}

// Eq. (2) for one point (direction u, bearing phi, range r from o): the bins ring by ring outward
// from phi, until no untested piece can win. After rings 0 .. j-1 every untested piece lies more
// than (j - 1) bin widths from phi, so an exact range match at a smaller bearing difference ends it.
RangeCandidate search_bins(const BearingBins& bins, const Point2& u, double phi, double r, double window,
                           double tan_window, std::vector<std::uint32_t>& stamp, std::uint32_t query) {
  const int center = bearing_bin(phi);
  const int rings = static_cast<int>(std::ceil((window + kBinPadding) / kBinWidth)) + 1;
  RangeCandidate best;
  for (int j = 0; j <= rings; ++j) {
    if (j >= 1 && best.difference <= kTie && best.tan_bearing <= std::tan((j - 1) * kBinWidth)) break;
    for (const int side : {-1, 1}) {
      if (j == 0 && side > 0) continue;
      const int bin = ((center + side * j) % kBearingBins + kBearingBins) % kBearingBins;
      for (std::uint32_t e = bins.offsets[bin]; e < bins.offsets[bin + 1]; ++e) {
        const std::uint32_t id = bins.ids[e];
        if (stamp[id] == query) continue;
        stamp[id] = query;
        test_piece(bins, id, u, r, tan_window, best);
      }
    }
  }
  return best;
}

}  // namespace

std::vector<std::optional<PolylinePoint>> matching_range_points(const ScanPolyline& target, const PointCloud2& source,
                                                                const SE2& T_target_source, double window,
                                                                double max_range_difference) {
  std::vector<std::optional<PolylinePoint>> matches(source.size());
  if (target.points.empty() || !(window > 0.0) || window >= kPi / 2.0) return matches;
  const BearingBins bins = bin_pieces(target, T_target_source.translation());
  const Eigen::Matrix2d R = T_target_source.rotation();
  const double tan_window = std::tan(window);
  std::vector<std::uint32_t> stamp(bins.pieces.size(), std::numeric_limits<std::uint32_t>::max());
  for (std::size_t i = 0; i < source.size(); ++i) {
    const Point2 v = R * source.points[i];  // m - o: the point seen from the source sensor
    const double r = v.norm();
    if (!(r > 1e-9)) continue;
    const Point2 u = v / r;
    const RangeCandidate best = search_bins(bins, u, fast_atan2(v.y(), v.x()), r, window, tan_window, stamp,
                                            static_cast<std::uint32_t>(i));
    if (!(best.difference <= max_range_difference)) continue;
    const Point2& qa = target.points[best.piece.a];
    const Point2 point = qa + best.s * (target.points[best.piece.b] - qa);
    matches[i] = PolylinePoint{.segment = best.piece.a, .s = best.s, .point = point, .distance = best.difference,
                               .bearing_difference = fast_atan2(best.local.y(), best.local.x())};
  }
  return matches;
}

// ---- Public building blocks ----

void validate(const ImrpConfig& c) {
  check_fields(c, "ImrpConfig");
  check(c.window_final <= c.window_initial, "ImrpConfig: window_final must be <= window_initial");
}

void validate(const IdcConfig& c) {
  check_fields(c, "IdcConfig");
  check(c.window_final <= c.window_initial, "IdcConfig: window_final must be <= window_initial");
  check(c.max_distance_final <= c.max_distance_initial, "IdcConfig: max_distance_final must be <= max_distance_initial");
}

std::optional<SE2> fit_rigid_motion(const std::vector<Point2>& a, const std::vector<Point2>& b,
                                    const std::vector<double>& weights) {
  if (a.size() < 2 || a.size() != b.size() || (!weights.empty() && weights.size() != a.size())) return std::nullopt;
  const auto weight = [&](std::size_t i) { return weights.empty() ? 1.0 : weights[i]; };
  double total = 0.0;
  Point2 a_mean = Point2::Zero();
  Point2 b_mean = Point2::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) {
    total += weight(i);
    a_mean += weight(i) * a[i];
    b_mean += weight(i) * b[i];
  }
  if (!(total > 0.0)) return std::nullopt;
  a_mean /= total;
  b_mean /= total;
  double s_xx = 0.0, s_yy = 0.0, s_xy = 0.0, s_yx = 0.0;  // S_xx', S_yy', S_xy', S_yx'
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Point2 da = weight(i) * (a[i] - a_mean);
    const Point2 db = b[i] - b_mean;
    s_xx += da.x() * db.x();
    s_yy += da.y() * db.y();
    s_xy += da.x() * db.y();
    s_yx += da.y() * db.x();
  }
  if (s_xx + s_yy == 0.0 && s_xy - s_yx == 0.0) return std::nullopt;  // all pairs coincide: no rotation
  const double w = std::atan2(s_xy - s_yx, s_xx + s_yy);             // Eq. (3)
  return SE2(b_mean - SE2(0.0, 0.0, w).rotation() * a_mean, w);       // Eq. (4)
}

// The normals of the target for the Fisher information: a total least squares line through each
// point and up to three neighbours on either side along the polyline. The two-point segment
// normals of a noisy scan near the sensor (1 cm noise over 2-4 cm spacing) tilt by tenths of a
// radian and would lend a corridor information along its axis.
PointCloud2 with_fitted_normals(const PointCloud2& target, double max_gap) {
  PointCloud2 fitted;
  fitted.points = target.points;
  estimate_normals_ordered(fitted, NormalEstimationConfig{.neighbors = 7, .max_neighbor_distance = max_gap,
                                                          .min_neighbors = 3});
  return fitted;
}

void finish_with_closest_points(const PointCloud2& target, const ScanPolyline& target_polyline,
                                const PointCloud2& source, double max_distance, double max_gap, double range_sigma,
                                MatchResult& result) {
  const SE2& T = result.T_target_source;
  std::vector<Correspondence> on_segments;  // point-to-line against the segment of the closest point
  std::vector<Correspondence> geometric;    // the same pairs against the fitted normal at their nearer end
  on_segments.reserve(source.size());
  geometric.reserve(source.size());
  double squared_sum = 0.0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const auto q = closest_point(target_polyline, T * source.points[i], max_distance);  // Eq. (1)
    if (!q) continue;
    squared_sum += q->distance * q->distance;
    const std::size_t k = q->segment;
    const bool on_segment = k + 1 < target_polyline.points.size() && target_polyline.connected[k];
    if (on_segment) on_segments.push_back({i, k, k + 1, 1.0});
    geometric.push_back({i, on_segment && q->s > 0.5 ? k + 1 : k, kNoPoint, 1.0});
  }
  result.inliers = geometric.size();
  result.residual = geometric.empty() ? 0.0 : std::sqrt(squared_sum / static_cast<double>(result.inliers));
  result.covariance = censi_covariance(target, source, T, on_segments, ErrorMetric::kPointToLine,
                                       SensorNoise{.range_sigma = range_sigma});
  const PointCloud2 fitted = with_fitted_normals(target, max_gap);
  apply(analyze_degeneracy(fitted, source, T, geometric, DegeneracyConfig{.range_sigma = range_sigma}), result);
  if (result.inliers < 3) result.converged = false;
}

// ---- The matchers ----

MatchResult match_imrp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                       const ImrpConfig& config) {
  validate(config);
  const ScanPolyline polyline = make_scan_polyline(target, config.max_gap);
  const auto min_pairs = static_cast<std::size_t>(config.min_correspondences);
  SE2 T = T_target_source_guess;
  MatchResult result;
  PoseCycle cycle(2);
  for (int k = 0; k < config.max_iterations; ++k) {
    const double window = shrinking(config.window_initial, config.window_final, config.window_decay, k);  // Eq. (6)
    const PointPairs pairs = matching_range_pairs(polyline, source, T, window, config.max_range_difference);  // Eq. (2)
    const std::optional<SE2> D = range_rule_motion(pairs, T.translation(), min_pairs);  // Eq. (3')
    if (!D) return unmatched(T_target_source_guess, k + 1);
    const SE2 next = *D * T;
    result.iterations = k + 1;
    result.converged = converged(T, next, config.translation_tolerance, config.rotation_tolerance,
                                 window == config.window_final, cycle);
    T = next;
    if (result.converged) break;
  }
  result.T_target_source = T;
  finish_with_closest_points(target, polyline, source, config.final_max_distance, config.max_gap, config.range_sigma,
                             result);
  return result;
}

MatchResult match_idc(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                      const IdcConfig& config) {
  validate(config);
  const ScanPolyline polyline = make_scan_polyline(target, config.max_gap);
  const auto min_pairs = static_cast<std::size_t>(config.min_correspondences);
  SE2 T = T_target_source_guess;
  MatchResult result;
  PoseCycle cycle(2);
  double max_distance = config.max_distance_initial;
  for (int k = 0; k < config.max_iterations; ++k) {
    const double window = shrinking(config.window_initial, config.window_final, config.window_decay, k);  // Eq. (6)
    max_distance = shrinking(config.max_distance_initial, config.max_distance_final, config.max_distance_decay, k);
    const PointPairs closest = closest_point_pairs(polyline, source, T, max_distance);  // Eq. (1)
    const PointPairs range = matching_range_pairs(polyline, source, T, window, config.max_range_difference);  // Eq. (2)
    const std::optional<SE2> range_motion = range_rule_motion(range, T.translation(), min_pairs);  // Eq. (3')
    if (closest.size() < min_pairs || !range_motion) return unmatched(T_target_source_guess, k + 1);
    const SE2 next = motion_given_rotation(closest, range_motion->theta()) * T;  // Eq. (5)
    result.iterations = k + 1;
    result.converged = converged(T, next, config.translation_tolerance, config.rotation_tolerance,
                                 window == config.window_final && max_distance == config.max_distance_final, cycle);
    T = next;
    if (result.converged) break;
  }
  result.T_target_source = T;
  finish_with_closest_points(target, polyline, source, max_distance, config.max_gap, config.range_sigma, result);
  return result;
}

}  // namespace slam2d
