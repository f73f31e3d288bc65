// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared pieces of the pose-graph tests.

#include <Eigen/Core>

#include "slam2d/optim/pose_graph.hpp"

namespace slam2d::test {

inline PoseGraphEdge make_edge(int from, int to, const SE2& T_from_to = SE2(),
                        const Eigen::Matrix3d& information = Eigen::Matrix3d::Identity(), bool robust = false) {
  PoseGraphEdge edge;
  edge.from = from;
  edge.to = to;
  edge.T_from_to = T_from_to;
  edge.information = information;
  edge.robust = robust;
  return edge;
}

}  // namespace slam2d::test
