// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/registration/match_fusion.hpp"

namespace slam2d {

MotionMeasurement match_measurement(const MatchResult& match, const MatchNoiseConfig& config) {
  MotionMeasurement measurement{match.T_target_source, match.covariance};
  if (!match.covariance.allFinite() || match.covariance.diagonal().maxCoeff() >= kUnknownVariance) {
    measurement.covariance = unknown_covariance();
    return measurement;
  }
  measurement.covariance += covariance_from_sigmas(config.floor_translation, config.floor_translation,
                                                   config.floor_rotation);
  if (match.degenerate && match.weak_direction.norm() > 0.0) {
    const Eigen::Vector3d w = match.weak_direction.normalized();
    measurement.covariance += config.degenerate_sigma * config.degenerate_sigma * w * w.transpose();
  }
  measurement.covariance = make_positive_definite(measurement.covariance);
  return measurement;
}

}  // namespace slam2d
