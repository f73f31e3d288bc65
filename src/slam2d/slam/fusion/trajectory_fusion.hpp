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
//             translation) taking D(t_k) and D(t_k+1)'s positions onto S_k and S_k+1's. Where
//             the dense end points lie within 5 cm (the robot stood or turned in place) or A_k
//             would scale by more than 50%, a similarity would magnify the dense path's noise:
//             the segment is blended, p(t) = (1 - s) R_k(D(t)) + s R_k+1(D(t)), R_k the rigid
//             motion S_k * D(t_k)^-1, which also passes through both sparse poses;
//   heading:  theta(t) = D(t).theta + (1 - s) c_k + s c_k+1, c_k = S_k.theta - D(t_k).theta
//             (wrapped), the correction at the sparse poses;
//   s:        the fraction of the segment's distance travelled by the dense path at t,
//             (d(t) - d(t_k)) / (d(t_k+1) - d(t_k)); where the dense path travels under 1 mm over
//             the segment (a turn in place), the fraction of its time, (t - t_k) / (t_k+1 - t_k).
// Dense poses before the first or after the last sparse pose move rigidly with its correction.
//
// Three choices depart from the paper, all measured better (docs/methods/fusion.md):
// - s by distance rather than time: a robot that stands still for part of a segment keeps its
//   dense relative motion exactly there (a standing Hector does not drift), and the correction
//   is spent where the robot moved. By time, the 0.2 s RPE of hector+rbpf was 1.4% above
//   Hector's on Intel; by distance it is below it.
// - alignment "interpolated" blends every segment as above instead of fitting a similarity: the
//   sparse poses are placed every 1/3 s, where the robot moves a few centimetres, and a
//   similarity on so short a span turns the sparse poses' noise into stretch.
// - correction_smoothing sigma > 0: before the segments are aligned, the corrections
//   C_k = S_k * D(t_k)^-1 (x, y, theta; theta unwrapped) are averaged over the anchors with the
//   Gaussian weights exp(-(t_j - t_k)^2 / 2 sigma^2) (to 4 sigma), and S_k replaced by
//   C'_k * D(t_k). The fused path then no longer passes exactly through each sparse pose, but
//   their centimetre noise stops bending the dense path every 1/3 s. sigma 0 is the paper's.

#include <array>
#include <cstddef>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/trajectory.hpp"

namespace slam2d {

enum class FusionAlignment {
  kSimilarity,    // the paper's: a similarity per segment (blended where it would not be one)
  kInterpolated,  // every segment blended: the anchors' rigid corrections interpolated
};
constexpr auto choices(FusionAlignment) {
  return std::array{Choice{"similarity", FusionAlignment::kSimilarity}, Choice{"interpolated", FusionAlignment::kInterpolated}};
}

// Defaults chosen leave-one-out on hector+graph over Intel, ACES and FR079: the smallest relation
// error whose 0.2 s RPE is no worse than Hector's, picked on two logs, checked on the third (each
// split picked the same values).
struct FusionConfig {
  FusionAlignment alignment = FusionAlignment::kInterpolated;
  double correction_smoothing = 0.5;
};

template <typename Fields>
void describe(Fields& f, FusionConfig& c) {
  f.choice("alignment", c.alignment, "how a dense segment is bent onto its two sparse poses");
  f.number("correction_smoothing", c.correction_smoothing, "s", at_least(0),
           "sigma of the Gaussian average of the sparse poses' corrections; 0: through every sparse pose");
}

void validate(const FusionConfig& config);

struct FusionStats {
  std::size_t sparse_used = 0;     // sparse poses inside the dense trajectory's time span
  std::size_t segments = 0;        // dense sub-trajectories between two of them
  std::size_t blended_segments = 0;  // of those, blended rather than a similarity (see above)
  double max_scale_change = 0.0;     // |scale - 1| over the similarity segments: how much the dense path was stretched
};

/// The fused trajectory: one pose per dense pose, same stamps and order. Both trajectories are
/// sorted by stamp first (a copy). Throws Error when either is empty or fewer than one sparse pose
/// falls within the dense trajectory's span.
Trajectory fuse_trajectories(const Trajectory& dense, const Trajectory& sparse, const FusionConfig& config = {},
                             FusionStats* stats = nullptr);

}  // namespace slam2d
