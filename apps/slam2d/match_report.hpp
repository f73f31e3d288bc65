// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How certain a scan match is, as the commands print it (odometry --covariance-csv, match): the
// 3x3 covariance (registration/covariance.hpp), its standard deviations, and the degeneracy verdict
// with its measure (registration/degeneracy.hpp).

#include <optional>
#include <string>

#include "json.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d::cli {

/// m: the translational standard deviation, the major semi-axis of the 1-sigma ellipse.
double translation_sigma(const Covariance3& covariance);
/// rad: the rotational standard deviation, sqrt(tt).
double rotation_sigma(const Covariance3& covariance);
/// The degeneracy measure: the smallest over the largest eigenvalue of the scaled information
/// (degeneracy.hpp; degenerate below its min_eigenvalue_ratio), none when the matcher made no analysis.
std::optional<double> eigenvalue_ratio(const MatchResult& match);

/// {xx, xy, xt, yy, yt, tt} (m^2, m rad, rad^2), and sigma_trans_m, sigma_theta_deg.
JsonObject covariance_json(const Covariance3& covariance);
/// {degenerate, eigenvalue_ratio, min_eigenvalue, weak_direction: {x, y, theta}}.
JsonObject degeneracy_json(const MatchResult& match);

/// The per-scan CSV of odometry --covariance-csv: its header line, and one row. `status` is
/// first | matched | failed | too_few_points; without a match the match's columns stay empty.
/// `target` is the index of the keyframe scan the scan was matched against (empty without a match):
/// the rows whose index is a later row's target are the keyframe chain the trajectory is built on.
std::string covariance_csv_header();
std::string covariance_csv_row(std::size_t index, double stamp, const std::string& status, const MatchResult* match,
                               std::optional<std::size_t> target = std::nullopt);

}  // namespace slam2d::cli
