// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/motion_model.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

constexpr double kTurnOnTheSpot = 0.01;  // m: shorter translations have no rot1

// The rotation that scales the noise: the angle to the forward or the backward direction.
double noise_angle(double rotation) {
  const double a = std::abs(normalize_angle(rotation));
  return std::min(a, std::numbers::pi - a);
}

}  // namespace

void validate(const OdometryMotionConfig& config) { check_fields(config, "OdometryMotionConfig"); }

OdometryControl decompose_odometry(const SE2& T_odom_previous, const SE2& T_odom_current) {
  const Eigen::Vector2d delta = T_odom_current.translation() - T_odom_previous.translation();
  OdometryControl u;
  u.trans = delta.norm();                                                                  // Eq. (5.35)
  u.rot1 = u.trans < kTurnOnTheSpot ? 0.0 : angle_difference(std::atan2(delta.y(), delta.x()), T_odom_previous.theta());  // Eq. (5.34)
  u.rot2 = normalize_angle(T_odom_current.theta() - T_odom_previous.theta() - u.rot1);     // Eq. (5.36)
  return u;
}

SE2 apply_odometry(const SE2& pose, const OdometryControl& u, Matrix3* J_pose, Matrix3* J_control) {
  const double heading = pose.theta() + u.rot1;
  const double c = std::cos(heading);
  const double s = std::sin(heading);
  if (J_pose != nullptr) {
    *J_pose << 1.0, 0.0, -u.trans * s,  //
        0.0, 1.0, u.trans * c,          //
        0.0, 0.0, 1.0;
  }
  if (J_control != nullptr) {
    *J_control << -u.trans * s, c, 0.0,  //
        u.trans * c, s, 0.0,             //
        1.0, 0.0, 1.0;
  }
  return SE2(pose.x() + u.trans * c, pose.y() + u.trans * s, heading + u.rot2);
}

Eigen::Matrix3d control_covariance(const OdometryControl& u, const OdometryMotionConfig& config) {
  const double r1 = noise_angle(u.rot1);
  const double r2 = noise_angle(u.rot2);
  const double t2 = u.trans * u.trans;
  const double min_rot = config.min_rotation_sigma * config.min_rotation_sigma;
  const double min_trans = config.min_translation_sigma * config.min_translation_sigma;
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  M(0, 0) = std::max(config.alpha1 * r1 * r1 + config.alpha2 * t2, min_rot);
  M(1, 1) = std::max(config.alpha3 * t2 + config.alpha4 * (r1 * r1 + r2 * r2), min_trans);
  M(2, 2) = std::max(config.alpha1 * r2 * r2 + config.alpha2 * t2, min_rot);
  return M;
}

SE2 sample_odometry_motion(const SE2& pose, const OdometryControl& u, const OdometryMotionConfig& config, Rng& rng) {
  return sample_odometry_motion(pose, u, control_covariance(u, config).diagonal().cwiseSqrt(), rng);
}

SE2 sample_odometry_motion(const SE2& pose, const OdometryControl& u, const Eigen::Vector3d& sigmas, Rng& rng) {
  OdometryControl noisy;  // Table 5.6, lines 5-7
  noisy.rot1 = u.rot1 - sigmas(0) * rng.normal();
  noisy.trans = u.trans - sigmas(1) * rng.normal();
  noisy.rot2 = u.rot2 - sigmas(2) * rng.normal();
  return apply_odometry(pose, noisy);  // lines 8-10
}

MotionPrediction predict_odometry_motion(const SE2& pose, const Covariance3& covariance, const OdometryControl& u,
                                         const OdometryMotionConfig& config) {
  Matrix3 G;
  Matrix3 V;
  MotionPrediction prediction;
  prediction.pose = apply_odometry(pose, u, &G, &V);
  const Eigen::Matrix3d Sigma = G * covariance * G.transpose() + V * control_covariance(u, config) * V.transpose();
  prediction.covariance = 0.5 * (Sigma + Sigma.transpose());
  return prediction;
}

namespace {

OdometryMotionConfig translation_noise_of(OdometryMotionConfig model) {
  model.alpha1 = model.alpha2 = model.min_rotation_sigma = 0.0;
  return model;
}

OdometryMotionConfig rotation_noise_of(OdometryMotionConfig model) {
  model.alpha3 = model.alpha4 = model.min_translation_sigma = 0.0;
  return model;
}

}  // namespace

MotionNoiseLearner::MotionNoiseLearner(const OdometryMotionConfig& model, const MotionNoiseLearningConfig& config)
    : model_(model),
      translation_noise_(translation_noise_of(model)),
      rotation_noise_(rotation_noise_of(model)),
      config_(config),
      translation_(config.window, config.min_scale, config.max_scale),
      rotation_(config.window, config.min_scale, config.max_scale),
      calibration_(config.calibration) {
  check_fields(config_, "MotionNoiseLearningConfig");
}

SE2 MotionNoiseLearner::corrected(const SE2& increment) const { return calibration_.corrected(increment); }

OdometryMotionConfig MotionNoiseLearner::model() const {
  const double t = translation_.scale();
  const double r = rotation_.scale();
  OdometryMotionConfig scaled = model_;
  scaled.alpha1 *= r * r;
  scaled.alpha2 *= r * r;
  scaled.min_rotation_sigma *= r;
  scaled.alpha3 *= t * t;
  scaled.alpha4 *= t * t;
  scaled.min_translation_sigma *= t;
  return scaled;
}

OdometryControl MotionNoiseLearner::move(const SE2& increment) {
  const OdometryControl u = decompose_odometry(SE2(), corrected(increment));
  if (!anchored_ || (config_.window <= 0.0 && config_.calibration.window <= 0.0)) return u;
  raw_.add(increment);
  // The covariance propagates linearly (G P G^T + V M V^T): the two shares add up to the model's.
  from_translation_ = predict_odometry_motion(stretch_, from_translation_, u, translation_noise_).covariance;
  const MotionPrediction rotation = predict_odometry_motion(stretch_, from_rotation_, u, rotation_noise_);
  from_rotation_ = rotation.covariance;
  stretch_ = rotation.pose;
  travelled_ += std::abs(u.trans);
  turned_ += std::abs(u.rot1) + std::abs(u.rot2);
  return u;
}

void MotionNoiseLearner::start(const SE2& pose, const Covariance3& covariance) {
  anchored_ = true;
  anchor_ = pose;
  anchor_covariance_ = covariance;
  stretch_ = SE2();
  raw_ = OdometryStretch{};
  from_translation_ = from_rotation_ = Covariance3::Zero();
  travelled_ = turned_ = 0.0;
}

namespace {

constexpr double kTiny = 1e-12;  // a variance this small teaches nothing

}  // namespace

// The residual is the odometry's drift beside the two measurements' noise; the translation's
// carries the rotation noise's share too, at its learnt scale.
void MotionNoiseLearner::learn_odometry_noise(const Eigen::Vector3d& e, const Covariance3& measured) {
  if (from_rotation_(2, 2) > kTiny) rotation_.observe(e.z() * e.z(), from_rotation_(2, 2), measured(2, 2));
  const double r2 = rotation_.scale() * rotation_.scale();
  if (planar_variance(from_translation_) > kTiny) {
    translation_.observe(0.5 * e.head<2>().squaredNorm(), planar_variance(from_translation_),
                         planar_variance(measured) + r2 * planar_variance(from_rotation_));
  }
}

// The raw stretch against the measured increment, the residuals' variance the measurements' and
// the odometry's noise at its learnt scales.
void MotionNoiseLearner::learn_calibration(const SE2& increment, const Covariance3& measured) {
  const double r2 = rotation_.scale() * rotation_.scale();
  const double t2 = translation_.scale() * translation_.scale();
  calibration_.observe(raw_.turn, raw_.path, raw_.displacement.translation(), increment.theta(), increment.translation(),
                       measured(2, 2) + r2 * from_rotation_(2, 2),
                       planar_variance(measured) + t2 * planar_variance(from_translation_) +
                           r2 * planar_variance(from_rotation_));
}

void MotionNoiseLearner::measured(const SE2& pose, const Covariance3& covariance) {
  if (!wants_measurement()) return;
  // A measurement of unknown uncertainty can neither end nor start a stretch.
  if (covariance.diagonal().maxCoeff() >= kUnknownVariance || !covariance.allFinite()) return restart();
  if (!anchored_) return start(pose, covariance);
  // In the anchor's frame: the measured increment with the two measurements' covariances against
  // the odometry's.
  const SE2 increment = anchor_.between(pose);
  const Covariance3 measured = rotate_covariance(anchor_covariance_ + covariance, -anchor_.theta());
  const Eigen::Vector3d e = motion_difference(stretch_, increment);
  if (e.allFinite()) {
    learn_odometry_noise(e, measured);
    learn_calibration(increment, measured);
  }
  start(pose, covariance);
}

void MotionNoiseLearner::measured(const std::optional<MatchResult>& match) {
  if (!wants_measurement()) return;
  if (!match) return restart();
  measured(match->T_target_source, match->covariance);
}

}  // namespace slam2d
