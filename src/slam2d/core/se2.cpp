// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/se2.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <ostream>

#include "slam2d/core/angles.hpp"

namespace slam2d {

namespace {

// d R(theta) / d theta, applied to p.
Eigen::Vector2d rotation_derivative_times(double c, double s, const Eigen::Vector2d& p) {
  return {-s * p.x() - c * p.y(), c * p.x() - s * p.y()};
}

// V(theta) of the SE2 exponential, t = V(theta) rho, written as [[a, -b], [b, a]],
// and the derivatives da/dtheta, db/dtheta. Taylor series near zero.
struct VMatrix {
  double a, b, da, db;
};

VMatrix v_matrix(double theta) {
  const double t2 = theta * theta;
  if (std::abs(theta) < 1e-4) {
    return {1.0 - t2 / 6.0, theta / 2.0 - theta * t2 / 24.0, -theta / 3.0, 0.5 - t2 / 8.0};
  }
  const double s = std::sin(theta);
  const double c = std::cos(theta);
  return {s / theta, (1.0 - c) / theta, (theta * c - s) / t2, (theta * s - (1.0 - c)) / t2};
}

}  // namespace

SE2::SE2(double x, double y, double theta) : SE2(Eigen::Vector2d(x, y), theta) {}

SE2::SE2(const Eigen::Vector2d& translation, double theta)
    : translation_(translation),
      theta_(normalize_angle(theta)),
      cos_(std::cos(theta_)),
      sin_(std::sin(theta_)) {}

SE2 SE2::from_vector(const Eigen::Vector3d& xytheta) { return SE2(xytheta.x(), xytheta.y(), xytheta.z()); }

Eigen::Matrix2d SE2::rotation() const {
  Eigen::Matrix2d r;
  r << cos_, -sin_, sin_, cos_;
  return r;
}

Eigen::Matrix3d SE2::matrix() const {
  Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
  m.topLeftCorner<2, 2>() = rotation();
  m.topRightCorner<2, 1>() = translation_;
  return m;
}

SE2 SE2::compose(const SE2& other, Matrix3* J_this, Matrix3* J_other) const {
  if (J_this) {
    J_this->setIdentity();
    J_this->block<2, 1>(0, 2) = rotation_derivative_times(cos_, sin_, other.translation_);
  }
  if (J_other) {
    J_other->setIdentity();
    J_other->topLeftCorner<2, 2>() = rotation();
  }
  return SE2(translation_ + rotation() * other.translation_, theta_ + other.theta_);
}

SE2 SE2::inverse(Matrix3* J_this) const {
  const Eigen::Matrix2d rt = rotation().transpose();
  if (J_this) {
    J_this->setZero();
    J_this->topLeftCorner<2, 2>() = -rt;
    // d(-R^T t)/d theta = -(dR/dtheta)^T t
    J_this->block<2, 1>(0, 2) = Eigen::Vector2d(sin_ * x() - cos_ * y(), cos_ * x() + sin_ * y());
    (*J_this)(2, 2) = -1.0;
  }
  return SE2(-(rt * translation_), -theta_);
}

SE2 SE2::between(const SE2& other, Matrix3* J_this, Matrix3* J_other) const {
  Matrix3 J_inverse;
  const SE2 this_inverse = inverse(J_this ? &J_inverse : nullptr);
  Matrix3 J_compose_first;
  const SE2 result = this_inverse.compose(other, J_this ? &J_compose_first : nullptr, J_other);
  if (J_this) *J_this = J_compose_first * J_inverse;
  return result;
}

Eigen::Vector2d SE2::act(const Eigen::Vector2d& point, Matrix23* J_this, Eigen::Matrix2d* J_point) const {
  if (J_this) {
    J_this->leftCols<2>().setIdentity();
    J_this->col(2) = rotation_derivative_times(cos_, sin_, point);
  }
  if (J_point) *J_point = rotation();
  return {cos_ * point.x() - sin_ * point.y() + translation_.x(),
          sin_ * point.x() + cos_ * point.y() + translation_.y()};
}

SE2 SE2::exp(const Eigen::Vector3d& xi, Matrix3* J_xi) {
  const double theta = xi.z();
  const VMatrix v = v_matrix(theta);
  const Eigen::Vector2d rho = xi.head<2>();
  const Eigen::Vector2d t(v.a * rho.x() - v.b * rho.y(), v.b * rho.x() + v.a * rho.y());
  if (J_xi) {
    J_xi->setZero();
    (*J_xi)(0, 0) = v.a;
    (*J_xi)(0, 1) = -v.b;
    (*J_xi)(1, 0) = v.b;
    (*J_xi)(1, 1) = v.a;
    (*J_xi)(0, 2) = v.da * rho.x() - v.db * rho.y();
    (*J_xi)(1, 2) = v.db * rho.x() + v.da * rho.y();
    (*J_xi)(2, 2) = 1.0;
  }
  return SE2(t, theta);
}

Eigen::Vector3d SE2::log(Matrix3* J_this) const {
  const VMatrix v = v_matrix(theta_);
  const double det = v.a * v.a + v.b * v.b;  // > 0 for |theta| < 2 pi
  const Eigen::Vector2d rho((v.a * x() + v.b * y()) / det, (-v.b * x() + v.a * y()) / det);
  const Eigen::Vector3d xi(rho.x(), rho.y(), theta_);
  if (J_this) {
    Matrix3 J_exp;
    exp(xi, &J_exp);
    *J_this = J_exp.inverse();
  }
  return xi;
}

Matrix3 SE2::adjoint() const {
  Matrix3 ad = Matrix3::Identity();
  ad.topLeftCorner<2, 2>() = rotation();
  ad(0, 2) = translation_.y();
  ad(1, 2) = -translation_.x();
  return ad;
}

bool SE2::is_approx(const SE2& other, double tolerance) const {
  return (translation_ - other.translation_).norm() <= tolerance &&
         std::abs(angle_difference(theta_, other.theta_)) <= tolerance;
}

SE2 interpolate(const SE2& a, const SE2& b, double s) {
  return SE2(a.translation() + s * (b.translation() - a.translation()),
             a.theta() + s * angle_difference(b.theta(), a.theta()));
}

SE2 pose_between_anchors(const SE2& T_map_a, const SE2& T_map_b, const SE2& motion_ab, const SE2& motion_a_pose) {
  const SE2 forward = T_map_a * motion_a_pose;
  const SE2 backward = T_map_b * motion_ab.between(motion_a_pose);
  constexpr double kMetresPerRadian = 1.0;
  const auto extent = [&](const SE2& motion) {
    return motion.translation().norm() + kMetresPerRadian * std::abs(motion.theta());
  };
  const double total = extent(motion_ab);
  const double fraction = total > 1e-9 ? std::clamp(extent(motion_a_pose) / total, 0.0, 1.0) : 0.0;
  return interpolate(forward, backward, fraction);
}

std::ostream& operator<<(std::ostream& os, const SE2& pose) {
  return os << "SE2(" << pose.x() << ", " << pose.y() << ", " << pose.theta() << ")";
}

}  // namespace slam2d
