#pragma once
// 2D pose graph files.
// - g2o: "VERTEX_SE2 id x y theta", "EDGE_SE2 from to dx dy dtheta I11 I12 I13 I22 I23 I33", "FIX id ...".
// - TORO: "VERTEX2 id x y theta", "EDGE2 from to dx dy dtheta I11 I12 I22 I33 I13 I23".
// Other g2o tags are skipped and counted. Files may be gzip-compressed; some carry edges only.

#include <Eigen/Core>
#include <cstddef>
#include <string>
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

/// Reads g2o or TORO (told apart by the tags). Throws ParseError("PATH:LINE: ...") on malformed
/// lines, duplicate vertex ids, or a file that mixes the two formats.
PoseGraphFile read_pose_graph(const std::string& path);
/// Atomic writes; numbers in shortest exact form, so a read gives back what was written.
void write_g2o(const std::string& path, const PoseGraphFile& graph);
void write_toro(const std::string& path, const PoseGraphFile& graph);

}  // namespace slam2d
