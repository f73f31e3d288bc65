// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Graph SLAM in the shape of Karto (K. Konolige, G. Grisetti, R. Kuemmerle, W. Burgard,
// B. Limketkai, R. Vincent, "Efficient sparse pose adjustment for 2D mapping", IROS 2010, whose
// front end is Karto's, with its delayed loop closure) with the time-based keyframes of the 2015
// indoor-localization study and a robust kernel on loop edges:
//
// 1. keyframes: a scan becomes a node when the robot moved min_distance or turned min_angle since
//    the last keyframe, or min_time passed (keyframes.hpp);
// 2. sequential constraints: every scan is tracked against a local occupancy-grid map by
//    Gauss-Newton on a map pyramid (Hector's matcher, slam/hector), with a prior at the odometry's
//    prediction weighed by the odometry's own uncertainty (its motion noise model, whose scale the
//    tracker learns from how well the matches agree with it) under a Cauchy kernel, so that the
//    scan carries the step where it is sure and the odometry where the scan says little (glass,
//    noise, a corridor); the tracked motion from the previous keyframe is the edge. Its covariance
//    is the match's at the new keyframe (`sequential_from_match`; registration/match_fusion.hpp:
//    the Hessian's, twice, for the two ends matched against one local map, on a small floor,
//    inflated along a degenerate direction), which holds the odometry's information through the
//    prior, once. A scan-to-map match does not drift from keyframe to keyframe as scan-to-scan
//    matches do, so the chain is stiff and the loop edges bend it only where it drifted. With
//    `odometry_edges` (off by default: with the weighed prior they count the odometry twice), an
//    odometry edge beside it: the guarded odometry's increment between the two keyframes, with the
//    covariance of the odometry's motion noise model (core/motion_fusion.hpp), whose scale is
//    learnt from how well the two edges agree; where the two disagree beyond their joint
//    uncertainty, the one surer along the difference stands alone. An increment the odometry guard
//    did not trust leaves that odometry edge out, and without odometry the sequential edge keeps
//    the fixed covariance of the floor;
// 3. loop closure: earlier keyframes near the pose estimate, grouped in chains, each chain's
//    local map searched over a large window by branch-and-bound, accepted above a response
//    threshold after a fine refinement; when the drift between the keyframe and a chain (a drift
//    model of the distance travelled and the angle turned along the graph's path between them)
//    outgrows that window, a global search over the whole drift; a large correction is confirmed
//    by a second keyframe and checked against the closures already there before it goes in; a
//    local closure is held back while later searches keep matching the same chain, replaced by a
//    better one, and goes in when they stop (loop_closure.hpp);
// 4. back end: sparse pose adjustment (optim/sparse_pose_adjustment.hpp), warm-started, after a
//    closure that closes a new loop or when the closures not yet optimised disagree with the
//    estimate (a revisit of a place closed before waits: defer_agreeing_closures), and at the end;
//    finish() first searches from the last keyframes the search interval skipped, so that a loop
//    closing at the end of a log closes.
// 5. lifelong (keyframes.redundant_radius > 0, the default): the data a run keeps is bounded by
//    place, not by time (slam_toolbox's lifelong mode, Cartographer's trimmer, in their simplest
//    form). A keyframe the loop closer is done with (searched or skipped by the search interval,
//    and too far back for a confirmation to need it) drops its points and scan when an older
//    keyframe that keeps its own lies within the radius and angle, and the graph links the two: a
//    loop edge near both, so that the path through it (along the two visits and the edge) is at
//    most 2 x loop_closure.min_path_distance. It stays a node; the older keyframe keeps its data for
//    good.
// Every scan gets a pose: keyframes their optimised node, the scans between two keyframes their
// tracked motion, bent to meet both optimised ends.

#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/scan_gaps.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/optim/sparse_pose_adjustment.hpp"
#include "slam2d/slam/graph/keyframes.hpp"
#include "slam2d/slam/graph/loop_closure.hpp"
#include "slam2d/registration/correlative_map_match.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"

namespace slam2d {

/// The tracker's configuration: Hector's, with a prior at the odometry's prediction weighed by the
/// odometry's own uncertainty (HectorSlamConfig::prior_from_motion_noise: the prediction's
/// covariance from the motion noise model whose scale the tracker learns from how the matches
/// agree with the odometry) under a Cauchy kernel, a retry within a quarter turn after a poor fit
/// (recovery_residual 0.25, as without odometry, where it searches every heading), and solution remapping
/// (HectorMatcherConfig::degeneracy_ratio 0.01), which keeps the directions a scan leaves open (a
/// corridor's axis) at the odometry, and the same for the translation the scan's own geometry leaves
/// open (HectorMatcherConfig::scan_degeneracy_ratio 0.01, as the RBPF's proposal: a corridor with
/// no edge within range, where the map's dots of its far walls would pin the scan; the simulated
/// hospital world's 24 m corridors, 10 s RPE 0.025-0.069 -> 0.016-0.030 m against the odometry's
/// 0.030-0.033, docs/methods/graph_slam.md). Until the first match, and where the odometry is not a sensor
/// of its own (Hector's poses: map_job), the prior is the fixed weak one (sigma 0.1 m, 0.058 rad).
/// Each trusted increment is corrected for the odometry's systematic error (distance and turn
/// scales, heading drift per metre) learnt from the tracker's matches over 1000 stretches of half a
/// metre, each error by what of it stands out of the fit's uncertainty (odometry_calibration,
/// core/motion_fusion.hpp; Intel's 0.06 rad/m nearly whole, ACES's odometry, which has none to
/// speak of, not at all: Intel 0.0204 -> 0.0177 m, the eight corrected logs' degraded ATE 0.68x).
/// A standing increment within a burst of scans is not confirmed against the last motion
/// (odometry_guard.confirm_burst 0, the guard's default; Hector's 5): the Cauchy kernel already
/// lets the scans pull the match off a prediction they refute, and a refutation drops the odometry
/// edge across it (Intel with the odometry shifted and 1 cm range noise, seeds 4-7 held out: over
/// all relations 0.286 m summed over twelve runs, 0.311 with it; docs/odometry_guard.md, "Bursts").
HectorSlamConfig default_tracking_config();

struct GraphSlamConfig {
  double min_range = 0.1;
  double max_range = 25.0;  // > min_range
  KeyframeConfig keyframes{};
  // The tracker's prediction is the odometry when the scans come with it, else the last pose
  // (Hector's no-odometry settings, without the prior and the remapping): tracking.prior itself
  // is ignored.
  HectorSlamConfig tracking = default_tracking_config();
  double sequential_sigma_translation = 0.002;  // the sequential edge's floor
  double sequential_sigma_rotation = 0.001;
  // The tracker's match covariance on top of the floor (false: the floor alone, a fixed covariance).
  // With the tracker's weighed prior that covariance holds the odometry's information once, so the
  // odometry edges are off by default: beside it they would count the odometry twice
  // (docs/fusion_by_uncertainty.md, "The tracker's prior weighed by the motion noise").
  bool sequential_from_match = true;
  double degenerate_sigma = 1.0;  // m (rad) added along a degenerate match's weak direction
  bool odometry_edges = false;
  OdometryNoiseConfig odometry_noise{};
  LoopClosureConfig loop_closure{};
  SparsePoseAdjustmentConfig back_end{.loop_kernel = {.type = RobustKernelType::kCauchy, .scale = 3.0}};
  // The back end's schedule. Karto optimises after every loop closure, so a run's cost grows with
  // its closures times its graph: ten passes over one route cost 19x (FR079) and 69x (Intel) the
  // CPU time of one. Here a closure that closes a loop the graph did not yet hold (no path along
  // its edges within 2 x loop_closure.min_path_distance) is optimised at once, as Karto does; one
  // along a place already closed (a revisit) waits while the loop edges not yet optimised agree
  // with the estimate: their summed e^T Omega e at the current poses within chi-square's quantile
  // (3 degrees of freedom an edge) at the standard normal quantile optimize_gate_z (3.09: 99.9 %).
  // Such closures would move the poses by less than their own noise, which the front end cannot
  // see; finish() always optimises. false: after every closure (Karto's schedule).
  bool defer_agreeing_closures = true;
  double optimize_gate_z = 3.09;
  // The optimisations during the run stop when a step changes the cost by less than this
  // fraction (the front end reads their poses to a centimetre); finish()'s final one at
  // back_end.relative_tolerance.
  double run_relative_tolerance = 1e-4;
  // An optimisation during the run whose new loop edges each close a cycle of at most local_reach
  // metres along the graph's edges frees only the nodes within the longest of those cycles (5 m
  // at least) of their ends, the others held where they are: such a closure corrects what lies
  // on its short cycle, and the
  // whole graph of a long run is tens of thousands of nodes (ten passes of Intel: 470
  // optimisations of 31,354 nodes, 63 s of 122). Longer cycles (a loop's first closure), large
  // corrections and finish() optimise the whole graph. 0: every optimisation is of the whole graph.
  double local_reach = 40.0;
  // A confirmed large correction goes in without the kernel. It is refused when the graph,
  // optimised with it (and with the refused ones that agree with it), no longer agrees (e^T Omega e
  // within chi-square's quantile, 3 dof, at optimize_gate_z) with more of the loop edges that agreed
  // before than it and those bring: the larger mutually consistent set of closures wins (PCM's
  // rule). A refused one is remembered and goes in with a later one it agrees with. false: it always
  // goes in.
  bool check_large_closures = true;
  // A gap in the scans (core/scan_gaps.hpp: the logger paused, the laser dropped out). Across it
  // only the odometry tells where the robot went, so:
  // - the tracker starts a new local map (the old one would pull the new scans onto the wrong
  //   place when the odometry is off), unless the loop closer's window over the odometry's drift
  //   (below) stays within the tracker's reach (gap.track_*);
  // - the scan becomes a keyframe whose edge holds the odometry's increment with the odometry's own
  //   drift over that time, measured before the gap (core/scan_gaps.hpp's odometry_drift_over
  //   against the graph's estimate since the last gap; on the sequential floor; heading sigma at
  //   most pi);
  // - the loop closer's drift bound across it is that drift, so a place before the gap is searched
  //   for as far as the odometry may be off, and a closure to it is confirmed as a large one.
  // Without odometry, or with less than a quarter of the gap's duration seen before it, the drift
  // is unbounded (the whole window of loop_closure.large's global search) and the edge's noise that
  // of a path of gap.speed x the gap's duration, which also counts as the distance travelled
  // across the gap (Keyframe::path_distance).
  ScanGapConfig gap{};
  double map_resolution = 0.05;
};

template <typename Fields>
void describe(Fields& f, GraphSlamConfig& c) {
  f.number("min_range", c.min_range, "m", at_least(0), "shorter readings are dropped from the keyframes' clouds (robot body)");
  f.number("max_range", c.max_range, "m", greater_than(0),
           "> min_range; longer readings are dropped (no-return beams always are)");
  f.section("keyframes", c.keyframes, "when a scan becomes a graph node");
  f.section("tracking", c.tracking, "the scan-to-map tracker (its prior and relocalization are ignored)");
  f.number("sequential_sigma_translation", c.sequential_sigma_translation, "m", greater_than(0),
           "standard deviation of a sequential edge's translation");
  f.number("sequential_sigma_rotation", c.sequential_sigma_rotation, "rad", greater_than(0), "... and rotation");
  f.flag("sequential_from_match", c.sequential_from_match,
         "add the tracker's match covariance (twice) to those sigmas (false: a fixed covariance)");
  f.number("degenerate_sigma", c.degenerate_sigma, "m", at_least(0),
           "sigma added along the weak direction of a degenerate tracker match");
  f.flag("odometry_edges", c.odometry_edges, "an odometry edge beside each sequential edge, when the scans come with odometry");
  f.section("odometry_noise", c.odometry_noise, "the odometry edges' motion noise model (core/motion_fusion.hpp)");
  f.section("loop_closure", c.loop_closure, "the loop closer");
  f.section("back_end", c.back_end, "the sparse pose adjustment");
  f.flag("defer_agreeing_closures", c.defer_agreeing_closures,
         "optimise after a closure only when the closures not yet optimised disagree with the estimate");
  f.number("optimize_gate_z", c.optimize_gate_z, "1", any_value(),
           "... beyond chi-square's quantile (3 dof an edge) at this standard normal quantile");
  f.number("run_relative_tolerance", c.run_relative_tolerance, "1", at_least(0),
           "the back end's relative_tolerance during the run (finish(): back_end.relative_tolerance)");
  f.number("local_reach", c.local_reach, "m", at_least(0),
           "an optimisation of loop edges closing cycles this short frees the nodes within their cycle of their ends (0: the whole graph)");
  f.flag("check_large_closures", c.check_large_closures,
         "a confirmed large correction goes in only if the loop edges already there agree with it (optimize_gate_z)");
  f.section("gap", c.gap, "gaps in the scans: where the tracker starts a new map and the odometry alone bridges");
  f.number("map_resolution", c.map_resolution, "m per cell", greater_than(0), "of the occupancy map built from the keyframes");
}

/// Throws Error for out-of-range values.
void validate(const GraphSlamConfig& config);

struct GraphSlamStep {
  SE2 T_map_robot;          // the current estimate of this scan's pose
  bool keyframe = false;    // the scan became a graph node
  bool matched = false;     // the tracker matched the scan (a map existed, the match was not degenerate)
  int loop_closures = 0;    // loop edges added at this scan
};

struct GraphSlamStats {
  std::size_t scans = 0;
  std::size_t keyframes = 0;
  std::size_t loop_closures = 0;        // loop edges (the large window, global searches, confirmations)
  std::size_t near_links = 0;           // loop edges to near chains (small window)
  std::size_t loop_attempts = 0;        // chains searched over the large window
  std::size_t global_searches = 0;      // searches over the whole drift uncertainty
  std::size_t global_closures = 0;      // closures first found by a global search, confirmed and gone in
  std::size_t large_closures = 0;       // large corrections confirmed and added (each adds two loop edges)
  std::size_t unconfirmed_closures = 0; // large corrections dropped for want of a confirmation
  std::size_t rejected_large_closures = 0;  // confirmed large corrections refused (and not gone in later)
  std::size_t final_search_closures = 0;  // loop edges added by finish()
  std::size_t held_replaced = 0;        // delayed: held closures replaced by a better one of the same chain
  std::size_t held_dropped = 0;         // delayed: closures dropped for a better one held to the same chain
  std::size_t optimizations = 0;
  std::size_t optimization_iterations = 0;  // LM iterations over all optimisations
  std::size_t deferred_optimizations = 0;   // closures whose optimisation was deferred (they agreed)
  std::size_t local_optimizations = 0;      // optimisations of the nodes around short cycles only (local_reach)
  std::size_t sequential_failures = 0;  // keyframes whose tracker match was degenerate
  std::size_t gaps = 0;                 // gaps in the scans (gap)
  std::size_t gaps_tracked_through = 0; // ... across which the tracker kept its map (gap.track_*)
  std::size_t contradicted_large_closures = 0;  // confirmed pairs refused by the old map's free space
  std::size_t released_keyframes = 0;   // lifelong: keyframes whose points were dropped
  std::size_t merged_nodes = 0;         // lifelong: of those, the nodes merged into their witness's
  std::size_t odometry_edges = 0;       // odometry edges beside the sequential ones
  MotionFusionStats fusion;             // the two edges of each keyframe step: consistent, or which was surer
  double optimization_seconds = 0.0;    // wall time of the back end
  double loop_seconds = 0.0;            // wall time of loop closing (searches and verification)
  double global_search_seconds = 0.0;   // wall time of the global searches (part of loop_seconds)
};

class GraphSlam {
 public:
  explicit GraphSlam(const GraphSlamConfig& config = {});

  /// Processes one scan; T_odom_robot is the odometry pose at the scan when the log has it (give
  /// it for every scan or for none: the tracker's prior is chosen at the first scan). Throws Error
  /// when odometry stops midway.
  GraphSlamStep add_scan(const LaserScan& scan, const std::optional<SE2>& T_odom_robot = std::nullopt);
  /// Searches for loop closures from every keyframe since the last large-window search (the last
  /// keyframes of a log, which the search interval skipped), closes a pending delayed loop or
  /// unconfirmed large correction when it can, and runs the final optimisation.
  void finish();

  /// One pose per scan added, stamped with the scan's stamp (keyframes optimised, the others
  /// interpolated between them).
  Trajectory trajectory() const;
  const PoseGraph& graph() const { return graph_; }
  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  /// The occupancy map of the keyframes' scans at their optimised poses.
  OccupancyMap map() const;
  const GraphSlamStats& stats() const { return stats_; }
  /// What the tracker's odometry guard found (empty before the first scan or without odometry).
  OdometryGuardStats odometry_stats() const { return tracker_ ? tracker_->odometry_stats() : OdometryGuardStats{}; }
  /// The tracker's scans whose matched motion the odometry refuted (HectorSlam::stuck_matches).
  std::size_t stuck_matches() const { return tracker_ ? tracker_->stuck_matches() : 0; }
  const GraphSlamConfig& config() const { return config_; }
  /// The learnt noise model that weighs the odometry: the odometry edges' when they are on, else
  /// the tracker's, whose prior it weighs.
  const OdometryNoiseModel& odometry_noise() const {
    return config_.odometry_edges || !tracker_ ? odometry_noise_ : tracker_->odometry_noise();
  }
  /// The odometry's systematic error the tracker learnt; null where it does not
  /// (tracking.odometry_calibration off, or no scan yet).
  const OdometryCalibration* odometry_calibration() const {
    return tracker_ && tracker_->calibrating() ? &tracker_->odometry_calibration() : nullptr;
  }

 private:
  struct ScanRecord {
    double stamp = 0.0;
    std::size_t keyframe = 0;   // the last keyframe at or before this scan
    SE2 T_keyframe_robot;       // the scan relative to that keyframe (tracked motion)
  };

  PointCloud2 scan_cloud(const LaserScan& scan) const;
  HectorStep track(const LaserScan& scan, const std::optional<SE2>& T_odom_robot);
  void add_keyframe(const LaserScan& scan, const SE2& estimate, const HectorStep& tracked,
                    const std::optional<SE2>& T_odom_robot, bool matched, double gap);
  Covariance3 sequential_covariance(const HectorStep& tracked) const;
  bool contradicted(const LoopClosure& closure) const;
  Drift odometry_drift_over(double duration) const;  // since the last gap (core/scan_gaps.hpp)
  Covariance3 gap_covariance(const SE2& increment, double gap, const Drift& drift) const;
  void accumulate_odometry(const HectorStep& tracked);
  void add_odometry_edge(PoseGraphEdge& sequential);
  int close_loops(std::size_t current, bool final);
  int add_closures(const std::vector<LoopClosure>& closures, bool final);
  void record_closure(const LoopClosure& closure, bool final);
  bool lifelong() const { return config_.keyframes.redundant_radius > 0.0; }
  // How far along the graph a loop edge links a keyframe to an older one: twice the recent chain
  // (delayed closure adds one edge per chain passed, 8-18 m apart on the simulated ring).
  double link_reach() const { return 2.0 * config_.loop_closure.min_path_distance; }
  void release_redundant();
  void recheck_near(std::size_t keyframe);
  void try_release(std::size_t keyframe);
  std::optional<std::size_t> linked_witness(std::size_t keyframe, std::size_t linked, std::size_t anchor) const;
  bool redundant(std::size_t keyframe, std::size_t older) const;
  void copy_loop_stats();
  void optimize(double relative_tolerance);
  void apply_merges();
  void follow_merges();
  void optimize_locally(double radius);
  double cycle_length(const PoseGraphEdge& edge, double reach) const;
  bool estimate_disagrees() const;
  std::vector<LoopClosure> supported_large_closures(const std::vector<LoopClosure>& large);
  SE2 current_pose() const;
  SE2 interpolated_pose(const ScanRecord& record) const;

  GraphSlamConfig config_;
  KeyframeSelector selector_;
  std::vector<Keyframe> keyframes_;
  std::vector<LaserScan> keyframe_scans_;  // for the map
  std::vector<SE2> keyframe_motion_;       // tracked motion from the previous keyframe
  std::vector<std::optional<SE2>> keyframe_odometry_;  // the odometry pose at each keyframe (when it came)
  std::vector<ScanRecord> scans_;
  PoseGraph graph_;
  SparsePoseAdjustment back_end_;
  LoopCloser loop_closer_;
  GraphSlamStats stats_;
  std::optional<HectorSlam> tracker_;  // made at the first scan, when it is known whether odometry comes
  SE2 T_tracker_keyframe_;             // the last keyframe in the tracker's map frame
  std::size_t release_checked_ = 0;  // lifelong: the first keyframe not yet checked for release
  OdometryNoiseModel odometry_noise_;
  ScanGapDetector gaps_;
  SE2 odometry_since_keyframe_;       // the odometry's increments since the last keyframe, composed
  bool odometry_intact_ = false;      // ... all trusted by the guard (and odometry came)
  std::size_t first_unoptimized_edge_ = 0;  // the edges from here on came after the last optimisation
  double pending_cycle_ = 0.0;  // m, the longest cycle along the graph their loop edges close (local_reach)
  // Large corrections refused (check_large_closures), each a confirmed pair, the newest last; one
  // goes in later when a new large correction it agrees with does.
  static constexpr std::size_t kRememberedRefusals = 8;
  std::vector<std::vector<LoopClosure>> refused_large_;
  std::size_t refused_global_closures_ = 0;  // of the refused ones, those a global search found
  // Merged nodes (keyframes.merge_released; apply_merges): by node, the node it joined and its pose there.
  struct NodeMerge {
    std::size_t into = 0;
    SE2 T_into_node;
  };
  std::vector<std::optional<NodeMerge>> merged_;
  std::vector<std::pair<std::size_t, std::size_t>> pending_merges_;  // (node, into) not yet applied
};

}  // namespace slam2d
