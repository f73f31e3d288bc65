#pragma once
// Loop closure for graph SLAM, as Karto does it (K. Konolige et al., IROS 2010, Sec. III; the
// search of W. Hess, D. Kohler, H. Rapp, D. Andor, "Real-time loop closure in 2D LIDAR SLAM",
// ICRA 2016, Sec. V):
// 1. candidates: earlier keyframes within a search radius of the new keyframe's estimate, the
//    radius grown by the position uncertainty accumulated since the last closure, leaving out the
//    recent chain (keyframes fewer than min_path_distance metres of travel back);
// 2. chains: the candidates grouped into runs of consecutive keyframes, at least min_chain_size
//    long (a single old scan is too weak a witness);
// 3. verification, nearest chain first: the chain's points rasterised into a local map, the new
//    scan searched over a large window by branch-and-bound, accepted above the response
//    threshold (min_score) and, after the fine refinement, when min_inlier_fraction of its points
//    lie on the chain's map; the covariance comes from the response.
// Chains the graph already links to the new keyframe (within min_path_distance along its edges,
// after an earlier closure) are not searched again over the large window; optionally they are
// matched over the small window of the sequential constraint instead (Karto's "near chains").
// Delayed loop closure (the 2015 study's change to Karto, optional): a verified closure is kept
// while the next keyframes' closures to the same chain keep improving the response, and added
// when they stop.

#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/slam/graph/keyframes.hpp"
#include "slam2d/slam/graph/scan_to_map.hpp"

namespace slam2d {

struct LoopClosureConfig {
  bool enabled = true;
  double search_radius = 4.0;        // m, > 0: candidates within this of the estimate ...
  double uncertainty_sigmas = 3.0;   // 1, >= 0: ... plus this many standard deviations of the accumulated uncertainty
  double max_search_radius = 12.0;   // m, >= search_radius
  double min_path_distance = 10.0;   // m, >= 0: the recent chain, left out
  int min_chain_size = 10;           // 1, >= 1 (Karto's loop match minimum chain size)
  int max_chains = 1;                // 1, >= 1: chains searched over the large window per keyframe, nearest first
  // Chains already linked in the graph (within min_path_distance along its edges) are not searched
  // over the large window again; up to this many of them are matched over the small window per
  // keyframe instead. Off by default: with the earlier local-map front end they bent FR079's map
  // (2.0 m mean relation error against 0.09 m without them) and helped Intel (0.019 m against 0.024 m).
  int max_near_chains = 0;           // 1, >= 0
  // The large window is searched from every n-th keyframe (Cartographer's sampling of constraint
  // searches, deterministic); near chains from every one. Every 8th keyframe (about every 1.6 m)
  // and one chain: FR079 (many revisits) takes 8.2-8.4 s instead of 23 s with every 2nd and two
  // chains, at 0.039 m instead of 0.037 m.
  int search_interval = 8;           // 1, >= 1
  double min_inlier_fraction = 0.7;  // 1, in [0, 1]: after refinement
  // A closure must pin the pose down (Karto's maximum variance of a loop match): in a corridor the
  // response is flat along the axis, and such a match says nothing about where along it we are.
  double max_translation_variance = 0.01;  // m^2, > 0: largest eigenvalue of the match's translation covariance
  bool reject_degenerate = true;           // the scene's Fisher information must constrain every direction
  double map_radius = 15.0;          // m, > 0: chain points this far beyond the search window from the estimate are left out
  bool delayed = false;              // delayed loop closure
  // The large window: +-4 m, +-0.35 rad. A +-90 deg window costs about 4x more (branch-and-bound
  // keeps it affordable) but on FR079 it lets symmetric rooms in: 0.087 m mean relation error
  // against 0.065 m.
  MapMatchConfig match{.correlative = {.resolution = 0.05, .sigma = 0.05, .window_x = 4.0, .window_y = 4.0,
                                       .window_theta = 0.35, .angular_step = 0.006, .min_score = 0.5},
                       .refinement = {.max_correspondence_distance = 0.3},
                       .max_refinement_shift = 0.3,
                       .min_sigma_translation = 0.01,
                       .min_sigma_rotation = 0.004,
                       .min_score_at_window_edge = 1.0};
  MapMatchConfig near_match{.min_score_at_window_edge = 1.0};  // for near chains: the sequential constraint's window
};

/// A verified closure: the edge (robust) and the response that accepted it.
struct LoopClosure {
  PoseGraphEdge edge;
  double score = 0.0;  // correlative response, the fraction of points on the chain's map
  std::size_t chain_begin = 0;  // keyframe indices [begin, end) of the chain
  std::size_t chain_end = 0;
  bool near = false;  // a near chain's link (small window), not a loop closed over the large window
};

/// Throws Error for out-of-range values.
void validate(const LoopClosureConfig& config);

/// The nodes reachable from `source` along edges whose translations sum to at most `max_distance`
/// (Dijkstra), as a flag per node.
std::vector<bool> nodes_within_graph_distance(const PoseGraph& graph, std::size_t source, double max_distance);

/// Runs of consecutive keyframe indices (sorted input) of at least `min_size` elements, as [begin, end).
std::vector<std::pair<std::size_t, std::size_t>> group_into_chains(const std::vector<std::size_t>& sorted_candidates,
                                                                   int min_size);

class LoopCloser {
 public:
  explicit LoopCloser(const LoopClosureConfig& config = {});

  /// Closures of keyframe `current` (its node's pose in the graph is the estimate) with earlier
  /// keyframes, given the extra search radius the accumulated uncertainty allows. With delayed
  /// closure the result may be a closure of an earlier keyframe held back until now.
  std::vector<LoopClosure> close(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, std::size_t current,
                                 double uncertainty_radius, std::size_t* attempts = nullptr);
  /// The closure still held back (delayed mode), released.
  std::optional<LoopClosure> release();

  const LoopClosureConfig& config() const { return config_; }

 private:
  std::vector<LoopClosure> verify(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, std::size_t current,
                                  double uncertainty_radius, std::size_t* attempts) const;
  std::optional<LoopClosure> match_chain(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                         std::size_t current, std::pair<std::size_t, std::size_t> chain,
                                         const MapMatchConfig& match_config) const;
  std::vector<LoopClosure> delay(std::vector<LoopClosure> verified);

  LoopClosureConfig config_;
  std::optional<LoopClosure> pending_;
};

}  // namespace slam2d
