// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/eval/relation_error.hpp"

#include <cmath>
#include <string>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/eval/detail/association.hpp"

namespace slam2d {

namespace {

void check_relations_finite(const std::vector<Relation>& relations) {
  for (std::size_t k = 0; k < relations.size(); ++k) {
    const Relation& r = relations[k];
    const bool finite = std::isfinite(r.stamp_from) && std::isfinite(r.stamp_to) && r.T_from_to.vector().allFinite();
    check(finite, "relation_error: relation " + std::to_string(k) + " has a non-finite stamp or pose");
  }
}

// Eq. (1): delta_ij (-) delta*_ij = (delta*_ij)^-1 * (x_i^-1 * x_j).
RelationError error_of_relation(std::size_t index, const SE2& T_world_i, const SE2& T_world_j, const SE2& T_i_j_truth) {
  const SE2 T_i_j_estimate = T_world_i.between(T_world_j);
  const SE2 D = T_i_j_truth.between(T_i_j_estimate);
  return {index, D.translation().norm(), std::abs(D.theta()), T_world_i, T_world_j};
}

// Eq. (2) and the tables of Sec. 5: statistics of the errors and of their squares.
void summarise(RelationErrorResult& result) {
  std::vector<double> translation;
  std::vector<double> rotation_deg;
  translation.reserve(result.errors.size());
  rotation_deg.reserve(result.errors.size());
  for (const RelationError& e : result.errors) {
    translation.push_back(e.translation);
    rotation_deg.push_back(rad_to_deg(e.rotation));
  }
  result.translation = compute_statistics(translation);
  result.rotation_deg = compute_statistics(rotation_deg);
  result.translation_squared = compute_statistics(squared(translation));
  result.rotation_squared_deg2 = compute_statistics(squared(rotation_deg));
}

}  // namespace

RelationErrorResult relation_error(const Trajectory& estimate, const std::vector<Relation>& relations,
                                   const RelationErrorConfig& config) {
  check_stamp_tolerance(config.stamp_tolerance, "relation_error");
  check_finite_trajectory(estimate, "relation_error: estimate");
  check_relations_finite(relations);
  const StampIndex index(estimate);
  RelationErrorResult result;
  result.errors.reserve(relations.size());
  for (std::size_t k = 0; k < relations.size(); ++k) {
    const Relation& relation = relations[k];
    const auto i = index.nearest(relation.stamp_from, config.stamp_tolerance);
    const auto j = index.nearest(relation.stamp_to, config.stamp_tolerance);
    if (!i || !j) {
      ++result.missing;
      continue;
    }
    result.errors.push_back(error_of_relation(k, estimate[*i].pose, estimate[*j].pose, relation.T_from_to));
  }
  result.relations = result.errors.size();
  summarise(result);
  return result;
}

}  // namespace slam2d
