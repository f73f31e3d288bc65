// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The fusion of a dense, locally accurate trajectory (Hector SLAM, one pose per scan) with a
// sparse, globally consistent one (graph SLAM or the particle filter on a subset of the scans),
// as the 2015 precise-indoor-localization pipeline does it: each dense sub-trajectory between two
// sparse poses gets the transform that aligns its end points with those sparse poses, and the
// headings are corrected by interpolating the sparse trajectory's heading corrections. The result
// is dense, passes through every sparse pose, and keeps the dense trajectory's local shape.
//
// Between sparse poses k and k+1 (stamps t_k < t_k+1), with D(t) the dense pose interpolated at
// t and S_k the sparse pose:
//   position: p(t) = A_k(D(t).position), A_k the similarity (rotation, uniform scale,
//             translation) taking D(t_k) and D(t_k+1)'s positions onto S_k and S_k+1's; when the
//             dense positions coincide (the robot stood), the rigid motion S_k * D(t_k)^-1;
//   heading:  theta(t) = D(t).theta + (1 - s) c_k + s c_k+1, s = (t - t_k) / (t_k+1 - t_k),
//             c_k = S_k.theta - D(t_k).theta (wrapped), the correction at the sparse poses.
// Dense poses before the first or after the last sparse pose move rigidly with its correction.

#include <cstddef>

#include "slam2d/core/trajectory.hpp"

namespace slam2d {

struct FusionStats {
  std::size_t sparse_used = 0;     // sparse poses inside the dense trajectory's time span
  std::size_t segments = 0;        // dense sub-trajectories between two of them
  std::size_t rigid_segments = 0;  // of those, aligned rigidly (the dense end points coincided)
  double max_scale_change = 0.0;   // |scale - 1| over the segments: how much the dense path was stretched
};

/// The fused trajectory: one pose per dense pose, same stamps and order. Both trajectories are
/// sorted by stamp first (a copy). Throws Error when either is empty or fewer than one sparse pose
/// falls within the dense trajectory's span.
Trajectory fuse_trajectories(const Trajectory& dense, const Trajectory& sparse, FusionStats* stats = nullptr);

}  // namespace slam2d
