// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A 2D pose graph as a g2o or TORO file lists it: vertices and edges by id, in file order, the
// ids a FIX line names. What io/pose_graph_io.hpp reads and writes and optim/pose_graph.hpp turns
// into the graph it optimises (and back).

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "slam2d/core/se2.hpp"

namespace slam2d {

struct GraphVertex {
  int id = 0;
  SE2 pose;  // T_world_vertex
};

struct GraphEdge {
  int from = 0;
  int to = 0;
  SE2 T_from_to;  // measured pose of `to` in the frame of `from`
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();  // (x, y, theta), symmetric
};

enum class PoseGraphFormat { kG2o, kToro };

struct PoseGraphFile {
  PoseGraphFormat format = PoseGraphFormat::kG2o;
  std::vector<GraphVertex> vertices;  // file order
  std::vector<GraphEdge> edges;       // file order
  std::vector<int> fixed;             // ids named by FIX lines
  std::size_t skipped_lines = 0;      // unknown tags
};

}  // namespace slam2d
