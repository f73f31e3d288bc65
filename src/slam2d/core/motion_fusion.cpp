// SPDX-License-Identifier: BSD-3-Clause
// One motion measured by the odometry and by a scan match, fused by information; see motion_fusion.hpp.

#include "slam2d/core/motion_fusion.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

bool unknown(const Covariance3& covariance) { return covariance.diagonal().maxCoeff() >= kUnknownVariance; }

}  // namespace

Eigen::Vector3d motion_difference(const SE2& a, const SE2& b) {
  Eigen::Vector3d d = b.vector() - a.vector();
  d.z() = angle_difference(b.theta(), a.theta());
  return d;
}

void validate(const OdometryNoiseConfig& config) {
  check_fields(config, "OdometryNoiseConfig");
  check(config.min_scale <= 1.0, "OdometryNoiseConfig: min_scale must be <= 1");
}

NoiseScaleEstimate::NoiseScaleEstimate(double window, double min_scale, double max_scale)
    : window_(window), min_scale_(min_scale), max_scale_(max_scale) {}

void NoiseScaleEstimate::observe(double residual2_per_dof, double model_variance, double other_variance) {
  if (window_ <= 0.0) return;
  ++observations_;
  const double weight = 1.0 / std::min(static_cast<double>(observations_), window_);
  double scale2 = scale_ * scale_;
  const double clip = kMotionGateChi2 / 3.0 * (scale2 * model_variance + other_variance);
  const double sample = (std::min(residual2_per_dof, clip) - other_variance) / model_variance;
  scale2 += weight * (std::clamp(sample, min_scale_ * min_scale_, max_scale_ * max_scale_) - scale2);
  scale_ = std::sqrt(scale2);
}

OdometryCalibration::OdometryCalibration(const OdometryCalibrationConfig& config) : config_(config) {
  check_fields(config_, "OdometryCalibrationConfig");
}

namespace {

// A residual beyond 3 sigma of the fit weighs (3 sigma / residual)^2 (Huber-like): a slip or a
// wrong match cannot drag the fit, and a real change still moves it.
double robust_weight(double residual, double variance) {
  const double r2 = residual * residual;
  return r2 > 9.0 * variance ? 9.0 * variance / r2 : 1.0;
}

// The non-negative garrote (L. Breiman, "Better subset regression using the nonnegative garrote",
// Technometrics 1995, in its orthogonal form): zero within `threshold`, shrunk by the factor
// 1 - (threshold / estimate)^2 beyond it, so an error far out of its uncertainty is corrected
// nearly whole and one near it hardly at all.
double garrote(double estimate, double threshold) {
  if (!(std::abs(estimate) > threshold)) return 0.0;
  const double ratio = threshold / estimate;
  return estimate * (1.0 - ratio * ratio);
}

}  // namespace

void OdometryCalibration::observe(double turn, double path, const Eigen::Vector2d& displacement, double measured_rotation,
                                  const Eigen::Vector2d& measured_displacement, double rotation_variance,
                                  double translation_variance) {
  if (config_.window <= 0.0 || !(rotation_variance > 0.0) || !(translation_variance > 0.0)) return;
  const bool finite = std::isfinite(turn) && std::isfinite(path) && displacement.allFinite() &&
                      std::isfinite(measured_rotation) && measured_displacement.allFinite();
  if (!finite) return;
  ++observations_;
  const double keep = 1.0 - 1.0 / std::max(config_.window, 1.0);
  const double prior = 1.0 / (config_.prior_sigma * config_.prior_sigma);
  // Rotation: true turn = scale * odometry turn + drift * path. The residual is regressed on the
  // measured motion, not on the odometry's: the odometry's noise is in the residual, and a
  // regressor carrying it too would shrink the estimates towards zero (errors in variables). So
  // measured - odometry = a * measured turn + b * measured length (signed as the path; the chord
  // of a stretch this short is its path), with scale = 1 / (1 - a) and drift = b / (1 - a) per
  // metre measured, the translation scale times that per metre of the odometry's.
  const Eigen::Vector2d h(measured_rotation, std::copysign(measured_displacement.norm(), path));
  const double e = normalize_angle(measured_rotation - turn);
  const double r = e - h.dot(rotation_);
  const double w = robust_weight(r, rotation_variance) / rotation_variance;
  rotation_information_ = keep * rotation_information_ + w * h * h.transpose();
  rotation_vector_ = keep * rotation_vector_ + w * e * h;
  rotation_scatter_.add(keep, w * r * r);
  const Eigen::Matrix2d normal = rotation_information_ + prior * Eigen::Matrix2d::Identity();
  rotation_ = normal.ldlt().solve(rotation_vector_);
  const Eigen::Matrix2d inverse = normal.inverse();
  for (int i = 0; i < 2; ++i) {
    const double sigma = std::sqrt(rotation_scatter_.variance(inverse(i, i)));
    applied_rotation_(i) = garrote(rotation_(i), config_.significance * sigma);
  }
  // Translation: the measured length m = scale * the odometry's displacement along the measured
  // one, l; m - l = c * m, scale = 1 / (1 - c). Along the measured direction, not the odometry's
  // length: a jitter of the odometry across its path would lengthen that, never shorten it.
  const double measured_length = measured_displacement.norm();
  if (measured_length < config_.min_distance) return;
  const double along = displacement.dot(measured_displacement) / measured_length;
  const double et = measured_length - along;
  const double rt = et - measured_length * translation_;
  const double wt = robust_weight(rt, translation_variance) / translation_variance;
  translation_information_ = keep * translation_information_ + wt * measured_length * measured_length;
  translation_vector_ = keep * translation_vector_ + wt * et * measured_length;
  translation_scatter_.add(keep, wt * rt * rt);
  translation_ = translation_vector_ / (translation_information_ + prior);
  const double sigma = std::sqrt(translation_scatter_.variance(1.0 / (translation_information_ + prior)));
  applied_translation_ = garrote(translation_, config_.significance * sigma);
}

double OdometryCalibration::translation_scale() const {
  return std::clamp(1.0 / (1.0 - applied_translation_), 1.0 - config_.max_correction, 1.0 + config_.max_correction);
}

double OdometryCalibration::rotation_scale() const {
  return std::clamp(1.0 / (1.0 - applied_rotation_.x()), 1.0 - config_.max_correction, 1.0 + config_.max_correction);
}

double OdometryCalibration::drift_per_metre() const {
  return std::clamp(translation_scale() * applied_rotation_.y() / (1.0 - applied_rotation_.x()), -config_.max_correction,
                    config_.max_correction);
}

namespace {

// Forwards positive: the heading drift of unequal wheels turns with the direction of travel.
double signed_distance(const SE2& increment) {
  const double distance = increment.translation().norm();
  return increment.x() < 0.0 ? -distance : distance;
}

}  // namespace

// Within the bounds believed on all three: a fit beyond them is not a wheel odometry's systematic
// error (a time-shifted or interpolated odometry's errors are heavy-tailed, and a forgetting fit
// follows them to any value), so nothing is corrected while it lasts.
bool OdometryCalibration::credible() const {
  if (!(translation_ < 1.0) || !(rotation_.x() < 1.0)) return false;
  const double translation = 1.0 / (1.0 - translation_);
  const double rotation = 1.0 / (1.0 - rotation_.x());
  const double drift = translation * rotation * rotation_.y();
  const double bound = config_.max_correction;
  return std::abs(translation - 1.0) <= bound && std::abs(rotation - 1.0) <= bound && std::abs(drift) <= bound;
}

SE2 OdometryCalibration::corrected(const SE2& increment) const {
  if (!credible()) return increment;
  const double extra = (rotation_scale() - 1.0) * increment.theta() + drift_per_metre() * signed_distance(increment);
  // The chord of an arc turns by half the arc's turn.
  const Eigen::Vector2d t = Eigen::Rotation2Dd(0.5 * extra) * (translation_scale() * increment.translation());
  return SE2(t.x(), t.y(), increment.theta() + extra);
}

void OdometryStretch::add(const SE2& increment) {
  displacement = displacement * increment;
  turn += increment.theta();
  path += signed_distance(increment);
}

void CalibrationStretches::add(bool usable, const SE2& increment, const Covariance3& increment_noise, const SE2& measured,
                               const Covariance3& measured_covariance, OdometryCalibration& calibration) {
  if (usable && anchored_) {
    raw_.add(increment);
    odometry_covariance_ += increment_noise;
    const SE2 motion = anchor_.between(measured);
    if (motion.translation().norm() < kOdometryStretchSpan && std::abs(motion.theta()) < kOdometryStretchSpan) return;
    const Covariance3 total = anchor_covariance_ + measured_covariance + odometry_covariance_;
    calibration.observe(raw_.turn, raw_.path, raw_.displacement.translation(), motion.theta(), motion.translation(),
                        total(2, 2), planar_variance(total));
  }
  *this = CalibrationStretches{};
  if (!usable) return;
  anchored_ = true;
  anchor_ = measured;
  anchor_covariance_ = measured_covariance;
}

OdometryNoiseModel::OdometryNoiseModel(const OdometryNoiseConfig& config)
    : config_(config),
      translation_scale_(config.window, config.min_scale, config.max_scale),
      rotation_scale_(config.window, config.min_scale, config.max_scale) {
  validate(config_);
}

double OdometryNoiseModel::sigma_translation(const SE2& increment) const {
  return config_.rest_translation + config_.translation_per_metre * increment.translation().norm() +
         config_.translation_per_radian * std::abs(increment.theta());
}

double OdometryNoiseModel::sigma_rotation(const SE2& increment) const {
  return config_.rest_rotation + config_.rotation_per_metre * increment.translation().norm() +
         config_.rotation_per_radian * std::abs(increment.theta());
}

Covariance3 OdometryNoiseModel::covariance(const SE2& increment) const {
  const double translation = translation_scale() * sigma_translation(increment);
  return covariance_from_sigmas(translation, translation, rotation_scale() * sigma_rotation(increment));
}

void OdometryNoiseModel::observe(const SE2& increment, const SE2& measured, const Covariance3& measured_covariance) {
  if (config_.window <= 0.0 || unknown(measured_covariance)) return;
  const Eigen::Vector3d e = motion_difference(increment, measured);
  if (!e.allFinite()) return;
  translation_scale_.observe(0.5 * e.head<2>().squaredNorm(), std::pow(sigma_translation(increment), 2),
                             planar_variance(measured_covariance));
  rotation_scale_.observe(e.z() * e.z(), std::pow(sigma_rotation(increment), 2), measured_covariance(2, 2));
}

FusedMotion fuse_motion(const MotionMeasurement& odometry, const MotionMeasurement& match, double gate_chi2) {
  // A measurement without information leaves the other as the fused one.
  if (unknown(match.covariance)) return {odometry.value, odometry.covariance, 0.0, FusionOutcome::kFused};
  if (unknown(odometry.covariance)) return {match.value, match.covariance, 0.0, FusionOutcome::kFused};
  const Eigen::Vector3d d = motion_difference(odometry.value, match.value);
  const Eigen::Matrix3d odometry_information = information_from_covariance(odometry.covariance);
  const Eigen::Matrix3d match_information = information_from_covariance(match.covariance);
  const double mahalanobis2 = d.dot((odometry.covariance + match.covariance).ldlt().solve(d));
  if (!(mahalanobis2 <= gate_chi2)) {  // they disagree: the one surer along the difference wins
    const bool odometry_surer = d.dot(odometry_information * d) > d.dot(match_information * d);
    if (odometry_surer) return {odometry.value, odometry.covariance, mahalanobis2, FusionOutcome::kOdometryWon};
    return {match.value, match.covariance, mahalanobis2, FusionOutcome::kMatchWon};
  }
  const Eigen::Matrix3d information = odometry_information + match_information;
  const Covariance3 covariance = make_positive_definite(information.inverse());
  const Eigen::Vector3d fused = odometry.value.vector() + covariance * match_information * d;
  return {SE2(fused.x(), fused.y(), fused.z()), covariance, mahalanobis2, FusionOutcome::kFused};
}

void MotionFusionStats::count(FusionOutcome outcome) {
  switch (outcome) {
    case FusionOutcome::kFused: ++fused; break;
    case FusionOutcome::kOdometryWon: ++odometry_won; break;
    case FusionOutcome::kMatchWon: ++match_won; break;
  }
}

}  // namespace slam2d
