// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The modular ICP pipeline (pipeline.hpp) from a YAML file, the shape of libpointmatcher's
// configurations (Pomerleau et al. 2013, Sec. 3; their evaluations/official_solutions/*.yaml):
//
//   matcher: pipeline                       # optional; when present it must be 'pipeline'
//   source_filters: [{kind: range_clip, min: 0.1, max: 25.0}, {kind: voxel, size: 0.05}]
//   target_filters: [{kind: normals, neighbors: 5}]
//   association: {kind: kdtree, max_distance: 1.0}
//   outlier_filters: [{kind: trimmed, ratio: 0.9}, {kind: median_factor, factor: 3.0}]
//   minimizer: point_to_line
//   convergence: {max_iterations: 40, translation: 1.0e-4, rotation: 1.0e-4}
//   min_inliers: 10
//   range_sigma: 0.01
//
// A missing key keeps the default of PipelineConfig (a missing list its default list; an empty
// list `[]` no filter). Each filter's keys are its struct's fields (pipeline_filters.hpp):
//   range_clip: min, max              voxel: size            random: ratio, seed
//   normals: neighbors, max_neighbor_distance, min_neighbors, ordered
//   max_distance: distance            trimmed: ratio
//   median_factor: factor, quantile   normal_angle: max_angle
// association: kind (kdtree | projective), max_distance; minimizer: point_to_point |
// point_to_line | point_to_plane (the same as point_to_line); convergence: max_iterations,
// translation, rotation, error_change. These are the structs' field tables (core/config_fields.hpp),
// read by io's read_config. A misspelt key, a key of another kind, a wrong type or an
// out-of-range value is a ParseError naming the file and the line.

#include <string>

#include "slam2d/io/config_file.hpp"
#include "slam2d/registration/pipeline.hpp"

namespace slam2d {

/// The configuration in `node` (the root of a file, or a sub-map). Throws ParseError.
PipelineConfig pipeline_config_from(const ConfigNode& node);

/// The configuration in a YAML file. Throws Error when unreadable, ParseError when invalid.
PipelineConfig load_pipeline_config(const std::string& yaml_path);

}  // namespace slam2d
