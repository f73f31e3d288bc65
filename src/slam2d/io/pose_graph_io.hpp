// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// 2D pose graph files.
// - g2o: "VERTEX_SE2 id x y theta", "EDGE_SE2 from to dx dy dtheta I11 I12 I13 I22 I23 I33", "FIX id ...".
// - TORO: "VERTEX2 id x y theta", "EDGE2 from to dx dy dtheta I11 I12 I22 I33 I13 I23".
// Other g2o tags are skipped and counted. Files may be gzip-compressed; some carry edges only.

#include <string>

#include "slam2d/core/pose_graph_file.hpp"

namespace slam2d {

/// Reads g2o or TORO (told apart by the tags). Throws ParseError("PATH:LINE: ...") on malformed
/// lines, duplicate vertex ids, or a file that mixes the two formats.
PoseGraphFile read_pose_graph(const std::string& path);
/// Atomic writes; numbers in shortest exact form, so a read gives back what was written.
void write_g2o(const std::string& path, const PoseGraphFile& graph);
void write_toro(const std::string& path, const PoseGraphFile& graph);

/// The format a file's name asks for: .g2o or .graph (TORO), either optionally + .gz. Throws Error
/// naming `path` for any other extension.
PoseGraphFormat pose_graph_format_of(const std::string& path);
/// write_g2o or write_toro, as pose_graph_format_of(path) says.
void write_pose_graph(const std::string& path, const PoseGraphFile& graph);

}  // namespace slam2d
