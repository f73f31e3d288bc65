// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// SE2: a rigid motion in the plane, as a small value type.
//
// A pose T_a_b maps points from frame b into frame a: p_a = T_a_b * p_b.
// Optional Jacobians are derivatives of the result's coordinates (x, y, theta) with respect to
// the arguments' coordinates (x, y, theta) (or of a point's (x, y)); exp takes the tangent vector
// (v_x, v_y, omega). Angles are kept normalised to [-pi, pi).

#include <Eigen/Core>
#include <iosfwd>

namespace slam2d {

using Matrix3 = Eigen::Matrix3d;
using Matrix23 = Eigen::Matrix<double, 2, 3>;

class SE2 {
 public:
  SE2() = default;
  SE2(double x, double y, double theta);
  SE2(const Eigen::Vector2d& translation, double theta);
  /// From the coordinate vector (x, y, theta).
  static SE2 from_vector(const Eigen::Vector3d& xytheta);
  static SE2 identity() { return SE2(); }

  double x() const { return translation_.x(); }
  double y() const { return translation_.y(); }
  double theta() const { return theta_; }
  const Eigen::Vector2d& translation() const { return translation_; }
  Eigen::Matrix2d rotation() const;
  /// The coordinate vector (x, y, theta).
  Eigen::Vector3d vector() const { return {translation_.x(), translation_.y(), theta_}; }
  /// The 3x3 homogeneous matrix.
  Eigen::Matrix3d matrix() const;

  /// this * other. J_this, J_other: d(result)/d(this), d(result)/d(other).
  SE2 compose(const SE2& other, Matrix3* J_this = nullptr, Matrix3* J_other = nullptr) const;
  /// this^-1. J_this: d(result)/d(this).
  SE2 inverse(Matrix3* J_this = nullptr) const;
  /// this^-1 * other: `other` expressed in the frame of `this`.
  SE2 between(const SE2& other, Matrix3* J_this = nullptr, Matrix3* J_other = nullptr) const;
  /// Applies the motion to a point: R p + t.
  Eigen::Vector2d act(const Eigen::Vector2d& point, Matrix23* J_this = nullptr,
                      Eigen::Matrix2d* J_point = nullptr) const;

  /// Group exponential of the tangent vector (v_x, v_y, omega). J_xi: d(result)/d(xi).
  static SE2 exp(const Eigen::Vector3d& xi, Matrix3* J_xi = nullptr);
  /// Group logarithm, the inverse of exp for |theta| < pi. J_this: d(xi)/d(this).
  Eigen::Vector3d log(Matrix3* J_this = nullptr) const;

  /// The adjoint matrix: exp(Ad * xi) = this * exp(xi) * this^-1.
  Matrix3 adjoint() const;

  SE2 operator*(const SE2& other) const { return compose(other); }
  Eigen::Vector2d operator*(const Eigen::Vector2d& point) const { return act(point); }

  /// Exact equality of the coordinates.
  bool operator==(const SE2& other) const {
    return translation_.x() == other.translation_.x() && translation_.y() == other.translation_.y() &&
           theta_ == other.theta_;
  }

  /// True when translations differ by at most `tolerance` (m) and angles by at most `tolerance` (rad).
  bool is_approx(const SE2& other, double tolerance = 1e-9) const;

 private:
  Eigen::Vector2d translation_ = Eigen::Vector2d::Zero();
  double theta_ = 0.0;
  double cos_ = 1.0;
  double sin_ = 0.0;
};

/// Linear interpolation of translation and shortest-path interpolation of the angle, s in [0, 1].
SE2 interpolate(const SE2& a, const SE2& b, double s);

/// A pose between two anchors a and b (keyframes, filter updates) placed in the map independently
/// of the motion between them: `motion_a_pose` (the pose's motion from a) carried forward from a
/// and backward from b (through `motion_ab`, the motion from a to b), blended by the fraction of
/// that motion done (translation plus 1 m per radian). A chain of such poses meets both anchors
/// and shares the correction at b between its links instead of jumping there.
SE2 pose_between_anchors(const SE2& T_map_a, const SE2& T_map_b, const SE2& motion_ab, const SE2& motion_a_pose);

std::ostream& operator<<(std::ostream& os, const SE2& pose);

}  // namespace slam2d
