// SPDX-License-Identifier: BSD-3-Clause
// Point-to-point ICP and accelerated ICP: P. J. Besl and N. D. McKay, "A method for
// registration of 3-D shapes", IEEE PAMI 14(2), 1992 (Sec. III-A closest points, Sec. III-C
// registration, Sec. IV the algorithm, Sec. IV-C its acceleration). See icp.hpp.

#include "slam2d/registration/icp.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/kd_tree.hpp"
#include "slam2d/registration/nearest_association.hpp"

namespace slam2d {
namespace {

constexpr std::size_t kMinPoints = 3;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Besl & McKay's registration vector q = [q_R | q_T] in the plane: the unit quaternion of a
// rotation about z, (q0, q3) = (cos(theta/2), sin(theta/2)) (Eq. (21), q1 = q2 = 0), and (t_x, t_y).
using RegistrationVector = Eigen::Vector4d;

RegistrationVector registration_vector(const SE2& T) {
  return {std::cos(T.theta() / 2.0), std::sin(T.theta() / 2.0), T.x(), T.y()};
}

SE2 from_registration_vector(const RegistrationVector& q) {
  return SE2(q(2), q(3), 2.0 * std::atan2(q(1), q(0)));  // q_R renormalised by the atan2
}

// Sec. IV-C, the accelerated ICP. The registrations trace a path q_1, q_2, ... in registration
// space; Delta q_k = q_k - q_{k-1}, and theta_k is the angle between Delta q_k and Delta q_{k-1}.
// When theta_k and theta_{k-1} are both below delta_theta, the last three states are well
// aligned: their errors d_k, d_{k-1}, d_{k-2} at the arc lengths v = 0, -|Delta q_k| and
// -|Delta q_k| - |Delta q_{k-1}| are fitted by a line (zero crossing v1) and a parabola (minimum
// v2), and q_k is replaced by q'_k = q_k + v Delta q_k / |Delta q_k|, v bounded by
// v_max = factor |Delta q_k|. q'_k then stands for q_k in the path, with its own error (found by
// the next association), so the next step is measured from it and a run of aligned steps is
// extrapolated again at once.
//
// The error d is Besl's d_k with every source point counted, a point without a pair (or farther
// than the gate) at the gate's square: D = (1/N) sum_i min(|R p_i + t - y_i|^2, gate^2). It is
// d_k when nothing is rejected, as in the paper, and it cannot drop by losing pairs.
//
// Guard (not in the paper, which keeps every extrapolation): the closest-point error at q'_k must
// not exceed D_k, the bound Besl's theorem gives for the error at q_k (closest points are no
// farther than the registered pairs). An extrapolation that does worse is undone, the path goes
// on from q_k, and the next registration is not extrapolated; the error along the path is then
// non-increasing, as in plain ICP.
class Accelerator {
 public:
  explicit Accelerator(const IcpConfig& config)
      : max_angle_(config.acceleration_angle), max_factor_(config.acceleration_max_factor) {}

  /// Registration k gave T_k (q_k) with error D_k: the state to go on from, T_k or q'_k.
  SE2 next(const SE2& T_k, double D_k) {
    q_ = {registration_vector(T_k), q_[0], q_[1]};
    d_ = {D_k, d_[0], d_[1]};
    T_k_ = T_k;
    if (++recorded_ < 3) return T_k;
    const RegistrationVector step = q_[0] - q_[1];
    const RegistrationVector previous_step = q_[1] - q_[2];
    theta_ = {angle_between(step, previous_step), theta_[0]};             // theta_k, theta_{k-1}
    const bool aligned = theta_[0] < max_angle_ && theta_[1] < max_angle_;
    if (!aligned || std::exchange(hold_, false)) return T_k;
    const double v = extrapolation(step.norm(), previous_step.norm());
    if (!(v > 0.0)) return T_k;
    extrapolated_ = q_[0] + v * step.normalized();                        // q'_k
    pending_ = true;
    return from_registration_vector(extrapolated_);
  }

  /// True when the last state returned is an extrapolation whose error is not yet known.
  bool pending() const { return pending_; }

  /// The guard, given the closest-point error D at the pending q'_k: true keeps q'_k in the path;
  /// false undoes it (go on from unaccelerated()).
  bool keep(double D) {
    pending_ = false;
    if (!(D <= d_[0])) {
      hold_ = true;
      return false;
    }
    q_[0] = extrapolated_;
    d_[0] = D;
    return true;
  }

  /// q_k, the registration the pending extrapolation started from.
  const SE2& unaccelerated() const { return T_k_; }

 private:
  static double angle_between(const RegistrationVector& a, const RegistrationVector& b) {
    const double norms = a.norm() * b.norm();
    if (!(norms > 0.0)) return kInfinity;
    return std::acos(std::clamp(a.dot(b) / norms, -1.0, 1.0));
  }

  // The step length v along Delta q_k (0: no extrapolation).
  double extrapolation(double step, double previous_step) const {
    const std::array<double, 3> v = {0.0, -step, -step - previous_step};
    // Line d = a1 v + b1 by least squares through the three points; v1 = -b1 / a1.
    const double v_mean = (v[0] + v[1] + v[2]) / 3.0;
    const double d_mean = (d_[0] + d_[1] + d_[2]) / 3.0;
    double covariance = 0.0;
    double variance = 0.0;
    for (int i = 0; i < 3; ++i) {
      covariance += (v[i] - v_mean) * (d_[i] - d_mean);
      variance += (v[i] - v_mean) * (v[i] - v_mean);
    }
    const double a1 = covariance / variance;
    const double v1 = a1 < 0.0 ? -(d_mean - a1 * v_mean) / a1 : -1.0;
    // Parabola d = a2 v^2 + b2 v + c2 through the three points (divided differences); v2 = -b2 / (2 a2).
    const double slope01 = (d_[1] - d_[0]) / (v[1] - v[0]);
    const double slope12 = (d_[2] - d_[1]) / (v[2] - v[1]);
    const double a2 = (slope12 - slope01) / (v[2] - v[0]);
    const double b2 = slope01 - a2 * v[1];
    const double v2 = a2 > 0.0 ? -b2 / (2.0 * a2) : -1.0;  // a minimum only
    const double v_max = max_factor_ * step;
    if (v2 > 0.0 && v2 < v1 && v2 < v_max) return v2;  // 0 < v2 < v1 < v_max or 0 < v2 < v_max < v1
    if (v1 > 0.0 && v1 < v_max) return v1;             // 0 < v1 < v2 < v_max, 0 < v1 < v_max < v2, v2 < 0 < v1 < v_max
    if (v1 >= v_max && v2 >= v_max) return v_max;
    return 0.0;
  }

  double max_angle_;
  double max_factor_;
  std::array<RegistrationVector, 3> q_ = {RegistrationVector::Zero(), RegistrationVector::Zero(),
                                          RegistrationVector::Zero()};  // q_k, q_{k-1}, q_{k-2}
  std::array<double, 3> d_ = {0.0, 0.0, 0.0};                           // D_k, D_{k-1}, D_{k-2}
  std::array<double, 2> theta_ = {kInfinity, kInfinity};                // theta_k, theta_{k-1}
  int recorded_ = 0;
  SE2 T_k_;
  RegistrationVector extrapolated_ = RegistrationVector::Zero();
  bool pending_ = false;
  bool hold_ = false;  // the last extrapolation was undone: do not extrapolate the next registration
};

// D of the accelerator: (1/N) sum min(|T p - y|^2, gate^2) over the N source points, the given
// pairs (T p_i, y_i) counted at their distance, the points without a pair at the gate.
double clipped_error(const SE2& T, const std::vector<Point2>& target_points, const std::vector<Point2>& source_points,
                     std::size_t source_size, double gate) {
  const double gate2 = gate * gate;
  double sum = static_cast<double>(source_size - source_points.size()) * gate2;
  for (std::size_t i = 0; i < source_points.size(); ++i) {
    sum += std::min((T * source_points[i] - target_points[i]).squaredNorm(), gate2);
  }
  return sum / static_cast<double>(source_size);
}

// The same at closest-point pairs already found (their squared distances).
double clipped_error(const std::vector<PointPair>& pairs, std::size_t source_size, double gate) {
  const double gate2 = gate * gate;
  double sum = static_cast<double>(source_size - pairs.size()) * gate2;
  for (const PointPair& pair : pairs) sum += std::min(pair.squared_distance, gate2);
  return sum / static_cast<double>(source_size);
}

// Buffers reused across iterations (no allocation once grown).
struct IcpBuffers {
  std::vector<PointPair> pairs;
  std::vector<Point2> target_points;
  std::vector<Point2> source_points;
};

}  // namespace

void validate(const IcpConfig& config) { check_fields(config, "IcpConfig"); }

MatchResult match_icp(const PointCloud2& target, const PointCloud2& source, const SE2& T_target_source_guess,
                      const IcpConfig& config) {
  validate(config);
  if (target.size() < kMinPoints || source.size() < kMinPoints) return unmatched(T_target_source_guess);
  const KdTree2 tree(target.points);
  const auto min_pairs = static_cast<std::size_t>(config.min_correspondences);
  const double gate = config.max_correspondence_distance;
  IcpBuffers buffers;
  Accelerator accelerator(config);
  MatchResult result;
  SE2 T = T_target_source_guess;
  double previous_mse = kInfinity;
  for (int k = 0; k < config.max_iterations; ++k) {
    // Y_k = C(P_k, X): closest points, far pairs rejected (Sec. III-A).
    associate_closest(tree, source.points, T, gate, buffers.pairs);
    if (accelerator.pending() && !accelerator.keep(clipped_error(buffers.pairs, source.size(), gate))) {
      T = accelerator.unaccelerated();  // the guard undid the extrapolation (Sec. IV-C)
      associate_closest(tree, source.points, T, gate, buffers.pairs);
    }
    if (buffers.pairs.size() < min_pairs) break;
    // (q_k, d_k) = Q(P_0, Y_k): the original points registered to their closest points (Sec. III-C).
    gather_pairs(buffers.pairs, target, source, SE2(), buffers.target_points, buffers.source_points);
    SE2 T_next = solve_point_to_point(config.solver, buffers.target_points, buffers.source_points);
    const double mse = mean_squared_distance(T_next, buffers.target_points, buffers.source_points);  // Eq. (22)
    if (config.accelerated) {  // Sec. IV-C
      T_next = accelerator.next(
          T_next, clipped_error(T_next, buffers.target_points, buffers.source_points, source.size(), gate));
    }
    result.iterations = k + 1;
    // Stop when d_{k-1} - d_k < tau (Sec. IV), or when the step is negligible.
    const bool done = std::abs(previous_mse - mse) < config.min_mse_change ||
                      step_below(T, T_next, config.min_translation_step, config.min_rotation_step);
    T = T_next;
    previous_mse = mse;
    if (done) {
      result.converged = true;
      break;
    }
  }
  // The final correspondences at the estimate.
  associate_closest(tree, source.points, T, gate, buffers.pairs);
  if (accelerator.pending() && !accelerator.keep(clipped_error(buffers.pairs, source.size(), gate))) {
    T = accelerator.unaccelerated();  // the loop ended on an extrapolation that does worse
    associate_closest(tree, source.points, T, gate, buffers.pairs);
  }
  result.T_target_source = T;
  if (buffers.pairs.size() < min_pairs) result.converged = false;
  finish_match(with_normals(target, tree), source, to_correspondences(buffers.pairs), ErrorMetric::kPointToPoint,
               min_pairs, result);
  return result;
}

}  // namespace slam2d
