// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Error figures added to a JSON summary; shared by `eval` and `demo`.

#include "json.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/eval/ate.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/eval/rpe.hpp"
#include "slam2d/io/relations.hpp"

namespace slam2d::cli {

/// relations, missing, trans_mean, trans_std, trans_max, rot_mean_deg, rot_std_deg, rot_max_deg,
/// trans_sq_mean, rot_sq_mean_deg2 (Kuemmerle et al. 2009).
RelationErrorResult add_relation_error(JsonObject& json, const Trajectory& estimate, const std::vector<Relation>& relations,
                                       double stamp_tolerance);

struct ReferenceError {
  AteResult ate;
  RpeResult rpe;  // over a travelled-distance window
};

/// matched, ate_rmse, ate_mean, ate_median, ate_max, rpe_delta_m, rpe_pairs, rpe_trans_rmse, rpe_trans_mean,
/// rpe_trans_max, rpe_rot_rmse_deg, rpe_rot_mean_deg, rpe_rot_max_deg.
ReferenceError add_reference_error(JsonObject& json, const Trajectory& estimate, const Trajectory& reference,
                         const RpeConfig& rpe_config);

}  // namespace slam2d::cli
