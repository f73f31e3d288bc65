// SPDX-License-Identifier: BSD-3-Clause
// SE2: group identities and every Jacobian against central finite differences.

#include "slam2d/core/se2.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <functional>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/rng.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

constexpr double kStep = 1e-6;
constexpr double kJacobianTolerance = 1e-6;

// Difference of two coordinate vectors (x, y, theta), with the angle wrapped.
Eigen::Vector3d coordinate_difference(const SE2& a, const SE2& b) {
  return {a.x() - b.x(), a.y() - b.y(), angle_difference(a.theta(), b.theta())};
}

// d f / d (coordinates of the argument), by central differences.
Matrix3 numeric_jacobian(const std::function<SE2(const Eigen::Vector3d&)>& f, const Eigen::Vector3d& at) {
  Matrix3 J;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d plus = at, minus = at;
    plus(k) += kStep;
    minus(k) -= kStep;
    J.col(k) = coordinate_difference(f(plus), f(minus)) / (2 * kStep);
  }
  return J;
}

std::vector<SE2> sample_poses() {
  Rng rng(7);
  std::vector<SE2> poses{SE2(), SE2(1.0, -2.0, 0.3), SE2(-3.0, 0.5, 3.1), SE2(0.2, 0.1, -3.1)};
  for (int i = 0; i < 20; ++i) {
    poses.emplace_back(rng.uniform(-10, 10), rng.uniform(-10, 10), rng.uniform(-3.14, 3.14));
  }
  return poses;
}

TEST(Se2, ConstructionNormalizesTheAngle) {
  EXPECT_NEAR(SE2(0, 0, 3 * std::numbers::pi).theta(), -std::numbers::pi, 1e-12);
  EXPECT_NEAR(SE2(0, 0, -0.5 - 4 * std::numbers::pi).theta(), -0.5, 1e-12);
  EXPECT_NEAR(SE2(0, 0, 7.0).theta(), 7.0 - 2 * std::numbers::pi, 1e-12);
}

TEST(Se2, ComposeMatchesHomogeneousMatrices) {
  const auto poses = sample_poses();
  for (std::size_t i = 0; i + 1 < poses.size(); ++i) {
    const Eigen::Matrix3d expected = poses[i].matrix() * poses[i + 1].matrix();
    EXPECT_TRUE((poses[i] * poses[i + 1]).matrix().isApprox(expected, 1e-12));
  }
}

TEST(Se2, InverseAndBetweenAreConsistent) {
  for (const SE2& a : sample_poses()) {
    EXPECT_TRUE((a * a.inverse()).is_approx(SE2(), 1e-12));
    EXPECT_TRUE((a.inverse() * a).is_approx(SE2(), 1e-12));
    const SE2 b(0.4, -1.2, 2.0);
    EXPECT_TRUE((a * a.between(b)).is_approx(b, 1e-12));
  }
}

TEST(Se2, ActMovesPointsLikeTheMatrix) {
  const SE2 T(1.0, 2.0, std::numbers::pi / 2);
  const Eigen::Vector2d p = T * Eigen::Vector2d(1.0, 0.0);
  EXPECT_NEAR(p.x(), 1.0, 1e-12);
  EXPECT_NEAR(p.y(), 3.0, 1e-12);
}

TEST(Se2, ExpAndLogAreInverse) {
  const std::vector<Eigen::Vector3d> tangents{
      {0.0, 0.0, 0.0}, {1.0, 0.5, 0.0}, {1.0, -2.0, 1e-9}, {0.3, 0.2, 1e-5}, {-1.0, 2.0, 3.0}, {2.0, 1.0, -2.5}};
  for (const auto& xi : tangents) {
    EXPECT_TRUE(SE2::exp(xi).log().isApprox(xi, 1e-9) || (SE2::exp(xi).log() - xi).norm() < 1e-12) << xi.transpose();
  }
  for (const SE2& T : sample_poses()) EXPECT_TRUE(SE2::exp(T.log()).is_approx(T, 1e-9));
}

TEST(Se2, ExpOfPureTranslationAndPureRotation) {
  EXPECT_TRUE(SE2::exp({1.0, 2.0, 0.0}).is_approx(SE2(1.0, 2.0, 0.0), 1e-15));
  // A quarter circle of radius 1: driving forward pi/2 while turning pi/2.
  EXPECT_TRUE(SE2::exp({std::numbers::pi / 2, 0.0, std::numbers::pi / 2}).is_approx(SE2(1.0, 1.0, std::numbers::pi / 2), 1e-12));
}

TEST(Se2, AdjointMovesTangentsAcrossFrames) {
  for (const SE2& T : sample_poses()) {
    const Eigen::Vector3d xi(0.3, -0.2, 0.4);
    EXPECT_TRUE(SE2::exp(T.adjoint() * xi).is_approx(T * SE2::exp(xi) * T.inverse(), 1e-9));
  }
}

TEST(Se2Jacobians, Compose) {
  for (const SE2& a : sample_poses()) {
    const SE2 b(0.7, -0.3, 1.1);
    Matrix3 J_a, J_b;
    a.compose(b, &J_a, &J_b);
    EXPECT_TRUE(J_a.isApprox(numeric_jacobian([&](const Eigen::Vector3d& v) { return SE2::from_vector(v) * b; }, a.vector()), kJacobianTolerance));
    EXPECT_TRUE(J_b.isApprox(numeric_jacobian([&](const Eigen::Vector3d& v) { return a * SE2::from_vector(v); }, b.vector()), kJacobianTolerance));
  }
}

TEST(Se2Jacobians, Inverse) {
  for (const SE2& a : sample_poses()) {
    Matrix3 J;
    a.inverse(&J);
    EXPECT_TRUE(J.isApprox(numeric_jacobian([](const Eigen::Vector3d& v) { return SE2::from_vector(v).inverse(); }, a.vector()), kJacobianTolerance));
  }
}

TEST(Se2Jacobians, Between) {
  for (const SE2& a : sample_poses()) {
    const SE2 b(-1.5, 2.5, -0.8);
    Matrix3 J_a, J_b;
    a.between(b, &J_a, &J_b);
    EXPECT_TRUE(J_a.isApprox(numeric_jacobian([&](const Eigen::Vector3d& v) { return SE2::from_vector(v).between(b); }, a.vector()), kJacobianTolerance));
    EXPECT_TRUE(J_b.isApprox(numeric_jacobian([&](const Eigen::Vector3d& v) { return a.between(SE2::from_vector(v)); }, b.vector()), kJacobianTolerance));
  }
}

TEST(Se2Jacobians, Act) {
  const Eigen::Vector2d p(2.0, -1.0);
  for (const SE2& a : sample_poses()) {
    Matrix23 J_pose;
    Eigen::Matrix2d J_point;
    a.act(p, &J_pose, &J_point);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d plus = a.vector(), minus = a.vector();
      plus(k) += kStep;
      minus(k) -= kStep;
      const Eigen::Vector2d numeric = (SE2::from_vector(plus).act(p) - SE2::from_vector(minus).act(p)) / (2 * kStep);
      EXPECT_TRUE(J_pose.col(k).isApprox(numeric, kJacobianTolerance) || (J_pose.col(k) - numeric).norm() < 1e-8);
    }
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d plus = p, minus = p;
      plus(k) += kStep;
      minus(k) -= kStep;
      const Eigen::Vector2d numeric = (a.act(plus) - a.act(minus)) / (2 * kStep);
      EXPECT_LT((J_point.col(k) - numeric).norm(), 1e-8);
    }
  }
}

TEST(Se2Jacobians, ExpAndLog) {
  const std::vector<Eigen::Vector3d> tangents{{0.5, -0.2, 0.0}, {0.5, -0.2, 1e-6}, {1.0, 2.0, 0.7}, {-2.0, 0.3, -2.9}};
  for (const auto& xi : tangents) {
    Matrix3 J_exp;
    SE2::exp(xi, &J_exp);
    EXPECT_LT((J_exp - numeric_jacobian([](const Eigen::Vector3d& v) { return SE2::exp(v); }, xi)).norm(), 1e-6) << xi.transpose();

    Matrix3 J_log;
    const SE2 T = SE2::exp(xi);
    T.log(&J_log);
    Matrix3 numeric;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d plus = T.vector(), minus = T.vector();
      plus(k) += kStep;
      minus(k) -= kStep;
      numeric.col(k) = (SE2::from_vector(plus).log() - SE2::from_vector(minus).log()) / (2 * kStep);
    }
    EXPECT_LT((J_log - numeric).norm(), 1e-6) << xi.transpose();
  }
}

TEST(Se2, InterpolateTakesTheShortWayRound) {
  const SE2 a(0, 0, 3.0), b(2, 0, -3.0);
  const SE2 mid = interpolate(a, b, 0.5);
  EXPECT_NEAR(mid.x(), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(mid.theta()), std::numbers::pi, 1e-9);
  EXPECT_TRUE(interpolate(a, b, 0.0).is_approx(a));
  EXPECT_TRUE(interpolate(a, b, 1.0).is_approx(b, 1e-12));
}

TEST(Se2, PoseBetweenAnchorsMeetsBothAnchorsAndSharesTheCorrection) {
  const SE2 T_map_a(1.0, 2.0, 0.3);
  const SE2 motion_ab(2.0, 0.0, 0.0);
  // Anchors consistent with the motion: every pose is the plain chain from a.
  const SE2 consistent_b = T_map_a * motion_ab;
  const SE2 midway(1.0, 0.0, 0.0);
  EXPECT_TRUE(pose_between_anchors(T_map_a, consistent_b, motion_ab, midway).is_approx(T_map_a * midway, 1e-12));
  // b corrected by 0.2 m sideways and 0.1 rad: the chain starts at a, ends at b, and halfway along
  // it is halfway between the forward and the backward chain.
  const SE2 T_map_b = consistent_b * SE2(0.0, 0.2, 0.1);
  EXPECT_TRUE(pose_between_anchors(T_map_a, T_map_b, motion_ab, SE2()).is_approx(T_map_a, 1e-12));
  EXPECT_TRUE(pose_between_anchors(T_map_a, T_map_b, motion_ab, motion_ab).is_approx(T_map_b, 1e-12));
  const SE2 forward = T_map_a * midway;
  const SE2 backward = T_map_b * motion_ab.between(midway);
  EXPECT_TRUE(pose_between_anchors(T_map_a, T_map_b, motion_ab, midway).is_approx(interpolate(forward, backward, 0.5), 1e-12));
  // Rotation counts 1 m per radian: a pure turn of 0.5 rad out of 1 rad is halfway too.
  const SE2 turn(0.0, 0.0, 1.0);
  const SE2 half_turn(0.0, 0.0, 0.5);
  const SE2 turned_b = T_map_a * turn * SE2(0.1, 0.0, 0.0);
  EXPECT_TRUE(pose_between_anchors(T_map_a, turned_b, turn, half_turn)
                  .is_approx(interpolate(T_map_a * half_turn, turned_b * turn.between(half_turn), 0.5), 1e-12));
  // No motion between the anchors: the forward chain.
  EXPECT_TRUE(pose_between_anchors(T_map_a, T_map_b, SE2(), SE2()).is_approx(T_map_a, 1e-12));
}

}  // namespace
}  // namespace slam2d
