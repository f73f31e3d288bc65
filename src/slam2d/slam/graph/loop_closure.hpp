// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Loop closure for graph SLAM, as Karto does it (K. Konolige et al., IROS 2010, Sec. III; the
// search of W. Hess, D. Kohler, H. Rapp, D. Andor, "Real-time loop closure in 2D LIDAR SLAM",
// ICRA 2016, Sec. V):
// 1. candidates: earlier keyframes within a search radius of the new keyframe's estimate, the
//    radius grown by the drift the two estimates may have gathered apart (DriftModel, along the
//    graph's shortest path between them), leaving out the recent chain (keyframes fewer than
//    min_path_distance metres of travel back);
// 2. chains: the candidates grouped into runs of consecutive keyframes, at least min_chain_size
//    long (a single old scan is too weak a witness);
// 3. verification, nearest chain first: the chain's points rasterised into a local map, the new
//    scan searched over a large window by branch-and-bound, accepted above the response
//    threshold (min_score) and, after the fine refinement, when min_inlier_fraction of its points
//    lie on the chain's map; the covariance comes from the response.
// Chains the graph already links to the new keyframe (within min_path_distance along its edges,
// after an earlier closure) are not searched again over the large window; optionally they are
// matched over the small window of the sequential constraint instead (Karto's "near chains").
// Delayed loop closure (Karto's rule, Konolige et al. 2010, Sec. III): a verified closure is held
// while later keyframes keep matching against the same chain (overlapping runs of earlier
// keyframes); a closure to that chain with a higher response replaces it, a lower one is dropped;
// it goes in when a large-window search no longer attempts the chain (the robot has left it) or
// at the end of the log. Only keyframes that search the large window (every search_interval-th)
// judge: the keyframes between them attempt nothing, which says nothing about where the robot is.
//
// Large corrections (LargeClosureConfig): a closure that moves the estimate by more than the
// robust kernel of the back end would follow (metres of drift) must be right, because it is
// added without the kernel and bends the whole loop. It must lie within the drift the model
// allows between the keyframe and the chain, and is held back until a second keyframe, at least
// confirm_min_distance away along the path, matches the old map at the pose the first closure's
// correction predicts, both under stricter thresholds; then both edges go in together. A large
// correction whose scan sees the chain's walls from behind (MatchResult::seen_from_behind) is
// refused; a small one is a thin wall's other face, where the map holds only the first.
// Global search: when the local search found nothing and chains lie around the estimate whose
// drift exceeds what the large window covers, those chains are searched by branch-and-bound over
// a window as wide as that drift (and as many headings), coarse to fine (a coarse table first,
// then the large window's resolution around its best pose, then the refinement); its closures are
// confirmed like large ones. Global searches run at most once every global_interval keyframes.
// finish() searches from every keyframe the interval skipped since the last search (a loop that
// closes at the end of a log).

#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "slam2d/core/scan_gaps.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/slam/graph/keyframes.hpp"
#include "slam2d/registration/correlative_map_match.hpp"

namespace slam2d {

/// How far two keyframes' estimates may have drifted apart: standard deviations that grow with
/// the distance travelled and the angle turned along the graph's shortest path between them
/// (sequential edges, and loop edges, which join revisits: a closure shortens the path to every
/// place it links), added up, not in quadrature (systematic drift, a scale or heading bias, adds
/// up linearly). Separate from the sequential edges' sigmas, which describe one keyframe-to-
/// keyframe match for the optimisation. The defaults, 3 sigmas = 5 % of the distance and
/// 0.0009 rad/m + 0.9 % of the turn in heading, hold the tracker's drift over 99.7-100 % of the
/// keyframe pairs of runs without closure on Intel (with and without odometry) and ACES with
/// odometry (ACES without: 94.8 %, its tracker jumps, which is no drift), checked on FR079
/// (99.9-100 %); see docs/methods/graph_slam.md.
struct DriftModel {
  double translation_per_metre = 0.0167;
  double rotation_per_metre = 0.0003;
  double rotation_per_radian = 0.003;
};

template <typename Fields>
void describe(Fields& f, DriftModel& c) {
  f.number("translation_per_metre", c.translation_per_metre, "m per m travelled", at_least(0), "translation drift");
  f.number("rotation_per_metre", c.rotation_per_metre, "rad per m travelled", at_least(0), "rotation drift from travel");
  f.number("rotation_per_radian", c.rotation_per_radian, "rad per rad turned", at_least(0), "rotation drift from turning");
}

/// The shortest path through a graph from a source node: the distance travelled (the edges'
/// translations) and the angle turned along it (the edges' rotations).
struct GraphPath {
  double distance = 0.0;  // m; infinity when unreachable
  double turned = 0.0;    // rad
};

/// The drift sigmas of a path.
Drift drift_along(const GraphPath& path, const DriftModel& model);

struct LargeClosureConfig {
  // A closure moving the estimate farther than either bound is a large correction: under the
  // back end's Cauchy kernel (scale 3 in sigmas of >= 1 cm and 0.004 rad) it would count for next
  // to nothing, so it is confirmed and added without the kernel instead. It must also lie within
  // the drift model's uncertainty_sigmas between the keyframe and the chain.
  double min_translation = 1.0;
  double min_rotation = 0.1;
  // Stricter thresholds than a local closure's, for both the first and the confirming match.
  double min_score = 0.6;
  double min_inlier_fraction = 0.8;
  // The confirmation: a keyframe this far on along the path (or back, at the end of a log),
  // matched at the first closure's correction over confirm_match's small window.
  double confirm_min_distance = 0.2;
  double confirm_max_distance = 8.0;  // >= confirm_min_distance
  // The second match must land this near the predicted pose (the motion between the two keyframes
  // is the tracker's, good to centimetres over a few metres).
  double confirm_tolerance = 0.25;
  double confirm_rotation_tolerance = 0.05;
  // A confirmed large correction is refused where the map before it contradicts the keyframes
  // since the last gap (or within verify_radius of the path back) moved by it: more than
  // max_contradiction of their walls on its free space (registration/free_space_check.hpp; the
  // old map: the keyframes within verify_radius of the match, up to the chain's end). 1: off.
  double max_contradiction = 0.15;
  double verify_distance = 0.2;
  double verify_radius = 8.0;
  MapMatchConfig confirm_match{.correlative = {.resolution = 0.05, .sigma = 0.05, .window_x = 0.5, .window_y = 0.5,
                                               .window_theta = 0.1, .angular_step = 0.004, .min_score = 0.5},
                               .refinement = {.max_correspondence_distance = 0.3},
                               .max_refinement_shift = 0.3,
                               .min_sigma_translation = 0.01,
                               .min_sigma_rotation = 0.004,
                               .min_score_at_window_edge = 1.0};
  // Global search.
  bool global_search = true;
  int global_interval = 16;
  double max_global_radius = 50.0;
  double max_global_window = 25.0;
  // Chains searched per global search, nearest the estimate first; the best closure wins. Where the
  // estimate is metres off (a gap in the scans, a long drift) the nearest chain need not be the
  // place: one chain let FR079 close on an office 17 m along its corridor after a gap (2.0 m over
  // all relations), two to eight found the right one (0.038 m; docs/methods/graph_slam.md).
  int max_global_chains = 4;
  // The coarse search (its window set per search) and the fine one around its pose
  // (registration/correlative_map_match.hpp's wide search).
  MapMatchConfig global_coarse = wide_search_coarse();
  MapMatchConfig global_fine = wide_search_fine();
};

template <typename Fields>
void describe(Fields& f, LargeClosureConfig& c) {
  f.number("min_translation", c.min_translation, "m", greater_than(0), "a closure moving the estimate farther is large ...");
  f.number("min_rotation", c.min_rotation, "rad", greater_than(0), "... or turning it more");
  f.number("min_score", c.min_score, "1", between(0, 1), "correlative response of both matches");
  f.number("min_inlier_fraction", c.min_inlier_fraction, "1", between(0, 1), "after refinement, both matches");
  f.number("confirm_min_distance", c.confirm_min_distance, "m", at_least(0),
           "the confirming keyframe lies at least this far along the path");
  f.number("confirm_max_distance", c.confirm_max_distance, "m", at_least(0),
           ">= confirm_min_distance: unconfirmed by then, dropped");
  f.number("confirm_tolerance", c.confirm_tolerance, "m", greater_than(0),
           "the second match must land this near the predicted pose ...");
  f.number("confirm_rotation_tolerance", c.confirm_rotation_tolerance, "rad", greater_than(0), "... and turned this near");
  f.number("max_contradiction", c.max_contradiction, "1", between(0, 1),
           "a confirmed correction is refused when more than this share of the recent keyframes' walls, moved by it, fall on the old map's free space");
  f.number("verify_distance", c.verify_distance, "m", greater_than(0), "a moved wall this near an old one agrees");
  f.number("verify_radius", c.verify_radius, "m", greater_than(0), "the keyframes checked: within this of the match (old) and along the path back (recent)");
  f.section("confirm_match", c.confirm_match, "the confirming match (small window)");
  f.flag("global_search", c.global_search, "search over the whole drift uncertainty");
  f.number("global_interval", c.global_interval, "keyframes", at_least(1), "at most one global search per this many");
  f.number("max_global_radius", c.max_global_radius, "m", greater_than(0),
           "candidates within search_radius + the drift radius, up to this");
  f.number("max_global_window", c.max_global_window, "m", greater_than(0),
           "translation half-width, the chain's drift radius up to this");
  f.number("max_global_chains", c.max_global_chains, "1", at_least(1), "chains searched per global search, nearest first");
  f.section("global_coarse", c.global_coarse, "the global search's coarse pass");
  f.section("global_fine", c.global_fine, "the fine search around the coarse pose, with the refinement");
}

struct LoopClosureConfig {
  bool enabled = true;
  // The local search takes candidates within search_radius of the estimate (its large window
  // covers a drift up to its half-width); the global search those within search_radius plus
  // uncertainty_sigmas standard deviations of the drift between them (DriftModel), up to
  // large.max_global_radius.
  double search_radius = 4.0;
  double uncertainty_sigmas = 3.0;
  double min_path_distance = 10.0;
  int min_chain_size = 10;  // Karto's loop match minimum chain size
  int max_chains = 1;
  // Chains already linked in the graph (within min_path_distance along its edges) are not searched
  // over the large window again; up to this many of them are matched over the small window per
  // keyframe instead. Off by default: small-window links to a chain already linked bent a map with
  // many revisits far more than they helped elsewhere (docs/defaults.md, with the figures).
  int max_near_chains = 0;
  // The large window is searched from every n-th keyframe (Cartographer's sampling of constraint
  // searches, deterministic); near chains from every one. Every 8th keyframe (about every 1.6 m)
  // and one chain: FR079 (many revisits) takes 8.2-8.4 s instead of 23 s with every 2nd and two
  // chains, at 0.039 m instead of 0.037 m.
  int search_interval = 8;
  double min_inlier_fraction = 0.7;
  // A closure must pin the pose down (Karto's maximum variance of a loop match): in a corridor the
  // response is flat along the axis, and such a match says nothing about where along it we are.
  double max_translation_variance = 0.01;
  bool reject_degenerate = true;
  double map_radius = 15.0;
  // Delayed loop closure (Karto's rule, above). On: better on each of Intel, ACES and FR079
  // (0.0178 / 0.0369 / 0.0375 m against 0.0182 / 0.0370 / 0.0387 m), chosen by leave-one-out
  // (docs/methods/graph_slam.md).
  bool delayed = true;
  DriftModel drift{};
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
  MapMatchConfig near_match{.min_score_at_window_edge = 1.0};
  LargeClosureConfig large{};
};

template <typename Fields>
void describe(Fields& f, LoopClosureConfig& c) {
  f.flag("enabled", c.enabled, "search for loop closures");
  f.number("search_radius", c.search_radius, "m", greater_than(0), "candidates within this of the estimate");
  f.number("uncertainty_sigmas", c.uncertainty_sigmas, "1", at_least(0),
           "the global search adds this many standard deviations of the drift");
  f.number("min_path_distance", c.min_path_distance, "m", at_least(0), "the recent chain, left out");
  f.number("min_chain_size", c.min_chain_size, "1", at_least(1), "fewest keyframes of a chain");
  f.number("max_chains", c.max_chains, "1", at_least(1), "chains searched over the large window per keyframe, nearest first");
  f.number("max_near_chains", c.max_near_chains, "1", at_least(0),
           "chains already linked matched over the small window per keyframe");
  f.number("search_interval", c.search_interval, "1", at_least(1), "the large window is searched from every n-th keyframe");
  f.number("min_inlier_fraction", c.min_inlier_fraction, "1", between(0, 1), "after refinement");
  f.number("max_translation_variance", c.max_translation_variance, "m^2", greater_than(0),
           "largest eigenvalue of the match's translation covariance");
  f.flag("reject_degenerate", c.reject_degenerate, "the scene's Fisher information must constrain every direction");
  f.number("map_radius", c.map_radius, "m", greater_than(0),
           "chain points this far beyond the search window from the estimate are left out");
  f.flag("delayed", c.delayed, "hold each chain's best closure until the robot leaves the chain (Karto)");
  f.section("drift", c.drift, "the odometry drift model of the global search");
  f.section("match", c.match, "the large window's match");
  f.section("near_match", c.near_match, "for near chains: the sequential constraint's window");
  f.section("large", c.large, "large corrections and the global search");
}

/// How a closure was found.
enum class LoopSearch {
  kLocal,         // the large window around the estimate
  kNear,          // a near chain's link (small window)
  kGlobal,        // the global search
  kConfirmation,  // the second keyframe of a large correction
};

/// A verified closure: the edge (robust unless it is a confirmed large correction) and the
/// response that accepted it.
struct LoopClosure {
  PoseGraphEdge edge;
  double score = 0.0;            // correlative response, the fraction of points on the chain's map
  double response = 0.0;         // Karto's response: mean Gaussian of the points' distances to the map
  double inlier_fraction = 0.0;  // after refinement
  std::size_t keyframe = 0;      // the keyframe the closure was searched from
  std::size_t anchor = 0;        // the chain's keyframe the edge starts at
  std::size_t chain_begin = 0;   // keyframe indices [begin, end) of the chain
  std::size_t chain_end = 0;
  LoopSearch search = LoopSearch::kLocal;
  SE2 T_map_matched;             // the keyframe's pose the match found (the estimate's frame when found)
  double correction_translation = 0.0;  // m, how far the match moves the keyframe from its estimate
  double correction_rotation = 0.0;     // rad

  bool near() const { return search == LoopSearch::kNear; }
};

/// What the searches did, for the run's summary.
struct LoopCloserStats {
  std::size_t attempts = 0;              // chains searched over the large window
  std::size_t held_replaced = 0;         // delayed: held closures replaced by a better one of the same chain
  std::size_t held_dropped = 0;          // delayed: closures dropped for a better one held to the same chain
  std::size_t global_searches = 0;
  std::size_t global_chains = 0;         // chains searched by global searches
  std::size_t global_closures = 0;       // confirmed closures first found by a global search
  std::size_t large_closures = 0;        // confirmed large corrections (global or local)
  std::size_t unconfirmed = 0;           // large corrections dropped for want of a confirmation
  double global_seconds = 0.0;           // wall time of the global searches
};

/// Throws Error for out-of-range values.
void validate(const DriftModel& model);
void validate(const LargeClosureConfig& config);
void validate(const LoopClosureConfig& config);

/// Per node, the step from the node before it where that step crosses a gap in the scans
/// (Keyframe::after_gap; graph SLAM's nodes are its keyframes, in order): the travel that the
/// model's drift would give the gap's (Keyframe::gap_drift_*), infinite where that is unknown.
std::vector<std::optional<GraphPath>> gap_steps(const std::vector<Keyframe>& keyframes, std::size_t nodes,
                                                const DriftModel& model);

/// The shortest paths (by distance travelled, Dijkstra) from the nearest of `sources` to every node,
/// up to `max_distance` (farther nodes: infinity). An edge between nodes n - 1 and n counts the step
/// `steps` (if given) holds for n instead of its own translation and rotation.
std::vector<GraphPath> graph_paths(const PoseGraph& graph, std::span<const std::size_t> sources,
                                   double max_distance = std::numeric_limits<double>::infinity(),
                                   const std::vector<std::optional<GraphPath>>* steps = nullptr);
inline std::vector<GraphPath> graph_paths(const PoseGraph& graph, std::size_t source,
                                          double max_distance = std::numeric_limits<double>::infinity(),
                                          const std::vector<std::optional<GraphPath>>* steps = nullptr) {
  return graph_paths(graph, std::span<const std::size_t>(&source, 1), max_distance, steps);
}

/// The nodes reachable from one of `sources` along edges whose translations sum to at most
/// `max_distance` (Dijkstra; `steps` as for graph_paths), as a flag per node.
std::vector<bool> nodes_within_graph_distance(const PoseGraph& graph, std::span<const std::size_t> sources,
                                              double max_distance,
                                              const std::vector<std::optional<GraphPath>>* steps = nullptr);
inline std::vector<bool> nodes_within_graph_distance(const PoseGraph& graph, std::size_t source, double max_distance,
                                                     const std::vector<std::optional<GraphPath>>* steps = nullptr) {
  return nodes_within_graph_distance(graph, std::span<const std::size_t>(&source, 1), max_distance, steps);
}

/// Runs of consecutive keyframe indices (sorted input) of at least `min_size` elements, as [begin, end).
std::vector<std::pair<std::size_t, std::size_t>> group_into_chains(const std::vector<std::size_t>& sorted_candidates,
                                                                   int min_size);

class LoopCloser {
 public:
  explicit LoopCloser(const LoopClosureConfig& config = {});

  /// Closures of keyframe `current` (its node's pose in the graph is the estimate) with earlier
  /// keyframes. With delayed closure the result may be a closure of an earlier keyframe held back
  /// until now; a confirmed large correction comes as two closures. `final`: searched from
  /// finish(), the large window (and a due global search) whatever the intervals.
  std::vector<LoopClosure> close(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, std::size_t current,
                                 bool final = false);
  /// The keyframes after the last one searched over the large window (finish() searches them).
  std::size_t first_unsearched() const { return last_searched_ ? *last_searched_ + 1 : 0; }
  /// At the end of a log: the closures still held back (delayed mode), released; a large
  /// correction still unconfirmed is dropped (the keyframes before it were tried when it was found).
  std::vector<LoopClosure> release();

  const LoopClosureConfig& config() const { return config_; }
  const LoopCloserStats& stats() const { return stats_; }

 private:
  using Chain = std::pair<std::size_t, std::size_t>;
  struct Uncertainty;  // per keyframe, from the current one

  Uncertainty uncertainty(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, std::size_t current) const;
  struct Verified {
    std::vector<LoopClosure> closures;
    std::vector<Chain> attempted;  // the chains searched over the large window, verified or not
  };

  Verified verify(const std::vector<Keyframe>& keyframes, const PoseGraph& graph, std::size_t current,
                  const Uncertainty& uncertainty, bool search_large_window);
  std::optional<LoopClosure> search_globally(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                             std::size_t current, const Uncertainty& uncertainty);
  std::optional<LoopClosure> confirm(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                     std::size_t current) const;
  std::optional<LoopClosure> confirm_before(const std::vector<Keyframe>& keyframes, const PoseGraph& graph) const;
  bool within_drift(const LoopClosure& closure, const Uncertainty& uncertainty) const;
  std::optional<LoopClosure> match_chain(const std::vector<Keyframe>& keyframes, const PoseGraph& graph,
                                         std::size_t current, Chain chain, const SE2& guess,
                                         const MapMatchConfig& match_config,
                                         const MapMatchConfig* coarse = nullptr) const;
  bool is_large(const LoopClosure& closure) const;
  bool passes_strict(const LoopClosure& closure) const;
  bool is_held(Chain chain) const;
  std::vector<LoopClosure> delay(const std::vector<LoopClosure>& verified, const std::vector<Chain>& attempted);
  std::vector<LoopClosure> confirmed(LoopClosure second);

  LoopClosureConfig config_;
  LoopCloserStats stats_;
  std::vector<LoopClosure> held_;            // delayed mode: the best closure so far of each chain
  std::optional<LoopClosure> pending_large_;  // a large correction waiting for its confirmation
  std::optional<std::size_t> last_searched_;  // the last keyframe searched over the large window
  std::optional<std::size_t> last_global_;    // the last keyframe a global search ran from
};

}  // namespace slam2d
