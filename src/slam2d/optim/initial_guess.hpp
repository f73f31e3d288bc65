// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The start of a pose graph's optimisation, orientations first: L. Carlone, R. Aragues,
// J. A. Castellanos, B. Bona, "A fast and accurate approximation for planar pose graph
// optimization", IJRR 33(7), 2014 (LAGO), in its simplest form.
// 1. The headings: each edge's measured turn, regularised by the multiple of 2 pi that the
//    spanning tree's headings give it (with_spanning_tree_poses), is a linear measurement of the
//    difference of two headings; all of them at once by weighted least squares (the weight the
//    edge's rotation variance), so that the loops' turns spread over the chain instead of the
//    odometry's being taken whole.
// 2. The positions: with the headings known, each edge's translation is linear in the two
//    positions (t_to - t_from = R_from t_measured), again all at once by weighted least squares.
// Both are sparse linear systems (Eigen's LDL^T). Gauss-Newton from the odometry's headings can
// stall where they have drifted far (a long corridor's small turn errors make the position
// residuals of a loop nonlinear); from here it starts near the optimum's headings.

#include "slam2d/optim/pose_graph.hpp"

namespace slam2d {

/// The graph with its poses estimated orientations first (above), from the fixed nodes. Nodes no
/// path joins to a fixed node keep their poses; where a linear system cannot be solved (a node
/// whose edges carry no rotation or translation information) the spanning tree's poses stand.
PoseGraph with_orientations_first_poses(const PoseGraph& graph);

}  // namespace slam2d
