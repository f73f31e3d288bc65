// SPDX-License-Identifier: BSD-3-Clause
// The 2D pose graph (Lu & Milios 1997) with the edge error of g2o (R. Kuemmerle, G. Grisetti,
// H. Strasdat, K. Konolige, W. Burgard, "g2o: A general framework for graph optimization",
// ICRA 2011) and SPA (Konolige et al. 2010, Eq. (1)-(3)): the measurement is compared with the
// relative pose of the two nodes in the frame of the measurement.
#include "slam2d/optim/pose_graph.hpp"

#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <unordered_map>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

// d R(theta)^T / d theta, applied to p.
Eigen::Vector2d rotation_transpose_derivative_times(double c, double s, const Eigen::Vector2d& p) {
  return {-s * p.x() + c * p.y(), -c * p.x() - s * p.y()};
}

// The node ids of a file in node order: the vertices in file order, then the ids that only edges
// name, in order of first appearance (from before to).
std::vector<int> node_ids(const PoseGraphFile& file, std::unordered_map<int, int>& index_of_id) {
  std::vector<int> ids;
  ids.reserve(file.vertices.size());
  const auto add = [&](int id) {
    if (index_of_id.emplace(id, static_cast<int>(ids.size())).second) ids.push_back(id);
  };
  for (const GraphVertex& vertex : file.vertices) add(vertex.id);
  for (const GraphEdge& edge : file.edges) {
    add(edge.from);
    add(edge.to);
  }
  return ids;
}

// The poses of the nodes not `known`, composed along the edges from the known ones (or, where
// none is known, from the first fixed node, else the first node, at its pose): a shortest-path
// tree (Dijkstra) that takes as few loop edges as it can, then as few edges. The odometry chain
// (edges between consecutive nodes) is what a graph is built along; a loop edge, possibly false,
// carries a pose only where the chain breaks. Returns the flags of the nodes reached.
std::vector<bool> compose_along_tree(PoseGraph& graph, std::vector<bool> known) {
  const std::size_t n = graph.size();
  std::vector<std::vector<int>> incident(n);  // edge indices by node
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    incident[graph.edges[k].from].push_back(static_cast<int>(k));
    incident[graph.edges[k].to].push_back(static_cast<int>(k));
  }
  const auto cost = [n](const PoseGraphEdge& edge) {
    return std::abs(edge.to - edge.from) == 1 ? 1.0 : static_cast<double>(n);
  };
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  std::vector<double> distance(n, std::numeric_limits<double>::infinity());
  for (std::size_t node = 0; node < n; ++node) {
    if (known[node]) queue.emplace(distance[node] = 0.0, static_cast<int>(node));
  }
  if (queue.empty() && n > 0) {
    std::size_t root = 0;
    while (root + 1 < n && !graph.is_fixed(root)) ++root;
    if (!graph.is_fixed(root)) root = 0;
    queue.emplace(distance[root] = 0.0, static_cast<int>(root));
  }
  while (!queue.empty()) {
    const auto [reached, node] = queue.top();
    queue.pop();
    if (reached > distance[node]) continue;  // a stale entry
    known[node] = true;
    for (int k : incident[node]) {
      const PoseGraphEdge& edge = graph.edges[k];
      const int other = edge.from == node ? edge.to : edge.from;
      const double through = reached + cost(edge);
      if (known[other] || through >= distance[other]) continue;
      distance[other] = through;
      graph.poses[other] = edge.from == node ? graph.poses[node] * edge.T_from_to
                                             : graph.poses[node] * edge.T_from_to.inverse();
      queue.emplace(through, other);
    }
  }
  return known;
}

// Initial poses of the nodes without a vertex, composed along the edges from the nodes with one
// (or, in an edges-only file, from the first fixed node or else the first node, at the origin).
void compose_missing_poses(const PoseGraphFile& file, PoseGraph& graph, std::vector<bool> known) {
  known = compose_along_tree(graph, std::move(known));
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    const PoseGraphEdge& edge = graph.edges[k];
    if (known[edge.from] && known[edge.to]) continue;
    const GraphEdge& named = file.edges[k];
    throw Error("pose graph: edge " + std::to_string(named.from) + " -> " + std::to_string(named.to) +
                " names a node without a vertex that no edge connects to a node with a pose");
  }
}

}  // namespace

// Eq. (1)-(2) (SPA) in g2o's form: e = t2v(Z^-1 (X_from^-1 X_to)), so
//   e_t = R_z^T (R_from^T (t_to - t_from) - t_z),  e_theta = theta_to - theta_from - theta_z.
Eigen::Vector3d edge_error(const PoseGraphEdge& edge, const SE2& T_world_from, const SE2& T_world_to,
                           Eigen::Matrix3d* J_from, Eigen::Matrix3d* J_to) {
  const Eigen::Matrix2d Rt_from = T_world_from.rotation().transpose();
  const double c = Rt_from(0, 0);
  const double s = Rt_from(0, 1);
  const Eigen::Matrix2d Rt_z = edge.T_from_to.rotation().transpose();
  const Eigen::Vector2d dt_world = T_world_to.translation() - T_world_from.translation();
  const Eigen::Vector2d t_from_to = Rt_from * dt_world;
  Eigen::Vector3d e;
  e.head<2>() = Rt_z * (t_from_to - edge.T_from_to.translation());
  e.z() = normalize_angle(T_world_to.theta() - T_world_from.theta() - edge.T_from_to.theta());
  if (J_from) {  // d e / d (x, y, theta)_from
    J_from->setZero();
    J_from->topLeftCorner<2, 2>() = -Rt_z * Rt_from;
    J_from->block<2, 1>(0, 2) = Rt_z * rotation_transpose_derivative_times(c, s, dt_world);
    (*J_from)(2, 2) = -1.0;
  }
  if (J_to) {  // d e / d (x, y, theta)_to
    J_to->setZero();
    J_to->topLeftCorner<2, 2>() = Rt_z * Rt_from;
    (*J_to)(2, 2) = 1.0;
  }
  return e;
}

double squared_error(const PoseGraphEdge& edge, const std::vector<SE2>& poses) {
  const Eigen::Vector3d e = edge_error(edge, poses[edge.from], poses[edge.to]);
  return e.dot(edge.information * e);
}

// Eq. (3): chi2 = sum e^T Omega e.
double chi2(const PoseGraph& graph) {
  const int n = static_cast<int>(graph.size());
  double sum = 0.0;
  for (const PoseGraphEdge& edge : graph.edges) {
    check(edge.from >= 0 && edge.from < n && edge.to >= 0 && edge.to < n, "chi2: edge node out of range");
    sum += squared_error(edge, graph.poses);
  }
  return sum;
}

PoseGraph to_pose_graph(const PoseGraphFile& file) {
  std::unordered_map<int, int> index_of_id;
  const std::vector<int> ids = node_ids(file, index_of_id);
  PoseGraph graph;
  graph.poses.assign(ids.size(), SE2());
  std::vector<bool> known(ids.size(), false);
  for (const GraphVertex& vertex : file.vertices) {
    const int node = index_of_id.at(vertex.id);
    graph.poses[node] = vertex.pose;
    known[node] = true;
  }
  graph.edges.reserve(file.edges.size());
  for (const GraphEdge& edge : file.edges) {
    graph.edges.push_back(PoseGraphEdge{.from = index_of_id.at(edge.from),
                                        .to = index_of_id.at(edge.to),
                                        .T_from_to = edge.T_from_to,
                                        .information = edge.information});
  }
  if (!file.fixed.empty()) {
    graph.fixed.assign(ids.size(), false);
    for (int id : file.fixed) {
      const auto it = index_of_id.find(id);
      check(it != index_of_id.end(), "pose graph: FIX names id " + std::to_string(id) + ", which no vertex or edge has");
      graph.fixed[it->second] = true;
    }
  }
  if (file.vertices.size() < ids.size()) compose_missing_poses(file, graph, std::move(known));
  return graph;
}

PoseGraph with_spanning_tree_poses(const PoseGraph& graph, std::vector<bool>* reached_nodes) {
  PoseGraph tree = graph;
  std::vector<bool> roots(graph.size(), false);
  for (std::size_t node = 0; node < graph.size(); ++node) roots[node] = graph.fixed.empty() ? node == 0 : graph.fixed[node];
  const std::vector<bool> reached = compose_along_tree(tree, std::move(roots));
  // A part of the graph that no edge joins to a fixed node keeps its own poses: composing it from
  // one of its nodes would only move it as a whole, which no edge measures.
  for (std::size_t node = 0; node < graph.size(); ++node) {
    if (!reached[node]) tree.poses[node] = graph.poses[node];
  }
  if (reached_nodes) *reached_nodes = reached;
  return tree;
}

PoseGraphFile to_pose_graph_file(const PoseGraph& graph, const PoseGraphFile& original) {
  std::unordered_map<int, int> index_of_id;
  const std::vector<int> ids = node_ids(original, index_of_id);
  check(ids.size() == graph.size(), "to_pose_graph_file: the graph has " + std::to_string(graph.size()) +
                                        " nodes, the original file " + std::to_string(ids.size()));
  PoseGraphFile file;
  file.format = original.format;
  file.fixed = original.fixed;
  file.vertices.reserve(ids.size());
  for (std::size_t node = 0; node < ids.size(); ++node) file.vertices.push_back({ids[node], graph.poses[node]});
  file.edges.reserve(graph.edges.size());
  for (const PoseGraphEdge& edge : graph.edges) {
    check(edge.from >= 0 && edge.from < static_cast<int>(ids.size()) && edge.to >= 0 &&
              edge.to < static_cast<int>(ids.size()),
          "to_pose_graph_file: edge node out of range");
    file.edges.push_back({ids[edge.from], ids[edge.to], edge.T_from_to, edge.information});
  }
  return file;
}

PoseGraphFile to_pose_graph_file(const PoseGraph& graph) {
  check(graph.fixed.empty() || graph.fixed.size() == graph.size(), "to_pose_graph_file: fixed has the wrong size");
  PoseGraphFile file;
  file.vertices.reserve(graph.size());
  for (std::size_t node = 0; node < graph.size(); ++node) {
    file.vertices.push_back({static_cast<int>(node), graph.poses[node]});
    if (!graph.fixed.empty() && graph.fixed[node]) file.fixed.push_back(static_cast<int>(node));
  }
  file.edges.reserve(graph.edges.size());
  for (const PoseGraphEdge& edge : graph.edges) {
    file.edges.push_back({edge.from, edge.to, edge.T_from_to, edge.information});
  }
  return file;
}

}  // namespace slam2d
