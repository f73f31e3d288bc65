// SPDX-License-Identifier: BSD-3-Clause
#include "match_report.hpp"

#include <fmt/core.h>

#include <cmath>

#include "slam2d/core/angles.hpp"

namespace slam2d::cli {
namespace {

// Shortest exact form; empty for NaN (a cell that has no value).
std::string cell(double value) { return std::isnan(value) ? std::string() : fmt::format("{}", value); }

}  // namespace

double translation_sigma(const Covariance3& covariance) { return translation_ellipse(covariance).major; }

double rotation_sigma(const Covariance3& covariance) { return std::sqrt(std::max(covariance(2, 2), 0.0)); }

std::optional<double> eigenvalue_ratio(const MatchResult& match) {
  const Eigen::Vector3d& e = match.information_eigenvalues;
  if (!e.allFinite()) return std::nullopt;
  return e.z() > 0.0 ? e.x() / e.z() : 0.0;
}

JsonObject covariance_json(const Covariance3& c) {
  JsonObject json;
  json.add("xx", c(0, 0)).add("xy", c(0, 1)).add("xt", c(0, 2)).add("yy", c(1, 1)).add("yt", c(1, 2)).add("tt", c(2, 2));
  json.add("sigma_trans_m", translation_sigma(c)).add("sigma_theta_deg", rad_to_deg(rotation_sigma(c)));
  return json;
}

JsonObject degeneracy_json(const MatchResult& match) {
  JsonObject json;
  json.add("degenerate", match.degenerate).add("eigenvalue_ratio", eigenvalue_ratio(match));
  const double smallest = match.information_eigenvalues.x();
  json.add("min_eigenvalue", std::isnan(smallest) ? std::nullopt : std::optional<double>(smallest));
  JsonObject weak;
  weak.add("x", match.weak_direction.x()).add("y", match.weak_direction.y()).add("theta", match.weak_direction.z());
  json.add("weak_direction", weak);
  return json;
}

std::string covariance_csv_header() {
  return "index,stamp,status,x,y,theta,converged,iterations,inliers,residual,"
         "cov_xx,cov_xy,cov_xt,cov_yy,cov_yt,cov_tt,sigma_trans,sigma_theta,"
         "degenerate,eigenvalue_ratio,min_eigenvalue,weak_x,weak_y,weak_theta,target\n";
}

std::string covariance_csv_row(std::size_t index, double stamp, const std::string& status, const MatchResult* match,
                               std::optional<std::size_t> target) {
  std::string row = fmt::format("{},{},{}", index, stamp, status);
  const std::string target_cell = target ? fmt::format(",{}\n", *target) : std::string(",\n");
  if (match == nullptr) return row + std::string(21, ',') + target_cell;
  const MatchResult& m = *match;
  const Covariance3& c = m.covariance;
  const double nan = std::nan("");
  row += fmt::format(",{},{},{},{:d},{},{},{}", m.T_target_source.x(), m.T_target_source.y(), m.T_target_source.theta(),
                     m.converged ? 1 : 0, m.iterations, m.inliers, m.residual);
  row += fmt::format(",{},{},{},{},{},{},{},{}", c(0, 0), c(0, 1), c(0, 2), c(1, 1), c(1, 2), c(2, 2),
                     translation_sigma(c), rotation_sigma(c));
  row += fmt::format(",{:d},{},{},{},{},{}", m.degenerate ? 1 : 0, cell(eigenvalue_ratio(m).value_or(nan)),
                     cell(m.information_eigenvalues.x()), m.weak_direction.x(), m.weak_direction.y(), m.weak_direction.z());
  return row + target_cell;
}

}  // namespace slam2d::cli
