// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Relation-based error metric of R. Kuemmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti,
// C. Stachniss, A. Kleiner: "On measuring the accuracy of SLAM algorithms", Autonomous Robots
// 27(4), 2009, Sec. 3, Eq. (1)-(2).
//
// For each ground-truth relation delta*_ij (the pose at t_j in the frame of the pose at t_i) the
// estimated relation is delta_ij = x_i^-1 * x_j, and the error is delta_ij (-) delta*_ij =
// (delta*_ij)^-1 * delta_ij. Its translational part |t| (m) and rotational part |theta| (rad)
// are summarised by mean, standard deviation and maximum, both of the absolute errors and of
// their squares (the paper's epsilon is the mean of the squares; its tables report both).

#include <cstddef>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/eval/statistics.hpp"
#include "slam2d/core/relation.hpp"

namespace slam2d {

struct RelationErrorConfig {
  double stamp_tolerance = 0.001;
};

template <typename Fields>
void describe(Fields& f, RelationErrorConfig& c) {
  f.number("stamp_tolerance", c.stamp_tolerance, "s", at_least(0),
           "a relation's stamps are matched to the trajectory pose with the nearest stamp within this");
}

/// The error of one evaluated relation.
struct RelationError {
  std::size_t relation_index = 0;  // into the relations vector
  double translation = 0.0;        // m, |t(D)|
  double rotation = 0.0;           // rad, |angle(D)|, in [0, pi]
  SE2 T_world_from;                // the estimate's poses at the relation's two stamps (where to draw it)
  SE2 T_world_to;
};

struct RelationErrorResult {
  std::size_t relations = 0;              // relations evaluated
  std::size_t missing = 0;                // relations left out because a stamp had no pose within the tolerance
  ErrorStatistics translation;            // m
  ErrorStatistics rotation_deg;           // deg
  ErrorStatistics translation_squared;    // m^2
  ErrorStatistics rotation_squared_deg2;  // deg^2
  std::vector<RelationError> errors;      // one per evaluated relation, in relation order
};

/// Evaluates `estimate` against the ground-truth `relations`. Poses are found by nearest stamp
/// (StampIndex, so the trajectory's stamps may be out of order). Statistics use the population
/// standard deviation and are zero when no relation could be evaluated (check `relations`).
/// Throws Error on a negative or non-finite tolerance or on non-finite input values.
RelationErrorResult relation_error(const Trajectory& estimate, const std::vector<Relation>& relations,
                                   const RelationErrorConfig& config = {});

}  // namespace slam2d
