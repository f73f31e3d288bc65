// SPDX-License-Identifier: BSD-3-Clause
#include "eval_summary.hpp"

#include "slam2d/eval/relation_error.hpp"

namespace slam2d::cli {

RelationErrorResult add_relation_error(JsonObject& json, const Trajectory& estimate, const std::vector<Relation>& relations,
                                       double stamp_tolerance) {
  const RelationErrorResult result = relation_error(estimate, relations, {.stamp_tolerance = stamp_tolerance});
  json.add("relations", result.relations).add("missing", result.missing);
  json.add("trans_mean", result.translation.mean).add("trans_std", result.translation.std);
  json.add("trans_max", result.translation.max);
  json.add("rot_mean_deg", result.rotation_deg.mean).add("rot_std_deg", result.rotation_deg.std);
  json.add("rot_max_deg", result.rotation_deg.max);
  json.add("trans_sq_mean", result.translation_squared.mean).add("trans_sq_std", result.translation_squared.std);
  json.add("rot_sq_mean_deg2", result.rotation_squared_deg2.mean);
  json.add("rot_sq_std_deg2", result.rotation_squared_deg2.std);
  return result;
}

ReferenceError add_reference_error(JsonObject& json, const Trajectory& estimate, const Trajectory& reference,
                                   const RpeConfig& rpe_config) {
  const AteResult ate = absolute_trajectory_error(estimate, reference, {.stamp_tolerance = rpe_config.stamp_tolerance});
  json.add("matched", ate.matched).add("ate_rmse", ate.rmse).add("ate_mean", ate.mean);
  json.add("ate_median", ate.median).add("ate_max", ate.max);
  const RpeResult rpe = relative_pose_error(estimate, reference, rpe_config);
  if (rpe_config.window == RpeWindow::kDistance) json.add("rpe_delta_m", rpe_config.delta);
  if (rpe_config.window == RpeWindow::kTime) json.add("rpe_delta_s", rpe_config.delta);
  json.add("rpe_pairs", rpe.pairs);
  json.add("rpe_trans_rmse", rpe.translation.rmse).add("rpe_trans_mean", rpe.translation.mean);
  json.add("rpe_trans_max", rpe.translation.max);
  json.add("rpe_rot_rmse_deg", rpe.rotation_deg.rmse).add("rpe_rot_mean_deg", rpe.rotation_deg.mean);
  json.add("rpe_rot_max_deg", rpe.rotation_deg.max);
  return {ate, rpe};
}

}  // namespace slam2d::cli
