#pragma once
// Graph SLAM in the shape of Karto (K. Konolige, G. Grisetti, R. Kuemmerle, W. Burgard,
// B. Limketkai, R. Vincent, "Efficient sparse pose adjustment for 2D mapping", IROS 2010, whose
// front end is Karto's) with the changes of the 2015 indoor-localization study (time-based
// keyframes, delayed loop closure) and a robust kernel on loop edges:
//
// 1. keyframes: a scan becomes a node when the robot moved min_distance or turned min_angle since
//    the last keyframe, or min_time passed (keyframes.hpp);
// 2. sequential constraint: the keyframe is matched against the recent keyframes rasterised into
//    a local map, correlative then refined (scan_to_map.hpp); the edge to the previous keyframe
//    carries the inverse of the match covariance;
// 3. loop closure: earlier keyframes near the pose estimate, grouped in chains, each chain's
//    local map searched over a large window by branch-and-bound, accepted above a response
//    threshold after a fine refinement (loop_closure.hpp);
// 4. back end: sparse pose adjustment after every loop closure and at the end
//    (optim/sparse_pose_adjustment.hpp), warm-started.
// Every scan gets a pose: keyframes their optimised node, the scans between two keyframes the
// odometry (or the matched motion) between them, bent to meet both optimised ends.

#include <cstddef>
#include <optional>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/optim/sparse_pose_adjustment.hpp"
#include "slam2d/slam/graph/keyframes.hpp"
#include "slam2d/slam/graph/loop_closure.hpp"
#include "slam2d/slam/graph/scan_to_map.hpp"

namespace slam2d {

/// The odometry's uncertainty over the motion from one keyframe to the next: the sequential
/// constraint fuses it with the match, so that directions the scan leaves open (a corridor's axis)
/// follow the odometry. Standard deviations grow linearly with the motion, from a floor.
struct OdometryNoise {
  double translation_floor = 0.02;   // m, > 0
  double translation_per_metre = 0.1;  // 1, >= 0
  double rotation_floor = 0.02;      // rad, > 0
  double rotation_per_radian = 0.1;  // 1, >= 0
  double rotation_per_metre = 0.05;  // rad/m, >= 0
};

/// The covariance (robot frame at the end of the motion, first order) of an odometry motion.
Covariance3 odometry_covariance(const SE2& motion, const OdometryNoise& noise);

/// The information-form fusion of a match (pose and covariance, map frame) with a prediction of
/// covariance `prediction_covariance` (the predicted pose's frame): the pose minimising both
/// Mahalanobis distances, and its covariance in the map frame.
ScanToMapResult fuse_with_prediction(const ScanToMapResult& match, const SE2& prediction,
                                     const Covariance3& prediction_covariance);

struct GraphSlamConfig {
  double min_range = 0.1;   // m, shorter readings are dropped (robot body)
  double max_range = 25.0;  // m, longer readings are dropped for matching (no-return beams always are)
  KeyframeConfig keyframes{};
  ScanToMapConfig sequential{};
  LoopClosureConfig loop_closure{};
  SparsePoseAdjustmentConfig back_end{.loop_kernel = {.type = RobustKernelType::kCauchy, .scale = 3.0}};
  double map_resolution = 0.05;      // m per cell of the occupancy map built from the keyframes
  double max_prior_dt = 1.0;         // s, without odometry constant velocity is not extrapolated over longer gaps
  double unmatched_sigma_translation = 0.1;  // m, > 0: the edge of a keyframe whose match failed (the prediction's)
  double unmatched_sigma_rotation = 0.05;    // rad, > 0
  OdometryNoise odometry_noise{};
};

/// Throws Error for out-of-range values.
void validate(const GraphSlamConfig& config);

struct GraphSlamStep {
  SE2 T_map_robot;          // the current estimate of this scan's pose
  bool keyframe = false;    // the scan became a graph node
  bool matched = false;     // its sequential match converged (keyframes only)
  int loop_closures = 0;    // loop edges added at this scan
};

struct GraphSlamStats {
  std::size_t scans = 0;
  std::size_t keyframes = 0;
  std::size_t loop_closures = 0;        // loop edges found over the large window
  std::size_t near_links = 0;           // loop edges to near chains (small window)
  std::size_t loop_attempts = 0;        // chains searched over the large window
  std::size_t optimizations = 0;
  std::size_t sequential_failures = 0;  // keyframes placed by the prediction alone
  double optimization_seconds = 0.0;
  double loop_seconds = 0.0;
};

class GraphSlam {
 public:
  explicit GraphSlam(const GraphSlamConfig& config = {});

  /// Processes one scan; T_odom_robot is the odometry pose at the scan when the log has it
  /// (without, the prediction is constant velocity from the last two keyframes' matches).
  GraphSlamStep add_scan(const LaserScan& scan, const std::optional<SE2>& T_odom_robot = std::nullopt);
  /// Closes a pending delayed loop and runs the final optimisation.
  void finish();

  /// One pose per scan added, stamped with the scan's stamp (keyframes optimised, the others
  /// interpolated between them).
  Trajectory trajectory() const;
  const PoseGraph& graph() const { return graph_; }
  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  /// The occupancy map of the keyframes' scans at their optimised poses.
  OccupancyMap map() const;
  const GraphSlamStats& stats() const { return stats_; }
  const GraphSlamConfig& config() const { return config_; }

 private:
  struct ScanRecord {
    double stamp = 0.0;
    std::size_t keyframe = 0;   // the last keyframe at or before this scan
    SE2 T_keyframe_robot;       // the scan relative to that keyframe (odometry or matched motion)
  };

  SE2 predict(const LaserScan& scan, const std::optional<SE2>& T_odom_robot) const;
  PointCloud2 scan_cloud(const LaserScan& scan) const;
  ScanToMapResult match_local_map(const PointCloud2& cloud, const SE2& guess);
  SE2 track(const PointCloud2& cloud, const SE2& prediction);
  const MatchMap& local_map();
  void add_keyframe(const LaserScan& scan, PointCloud2 cloud, const SE2& prediction, const ScanToMapResult& match);
  int close_loops();
  void add_closure(const LoopClosure& closure);
  void rebuild_local_map();
  void optimize();
  SE2 current_pose() const;
  SE2 interpolated_pose(const ScanRecord& record) const;

  GraphSlamConfig config_;
  KeyframeSelector selector_;
  std::vector<Keyframe> keyframes_;
  std::vector<LaserScan> keyframe_scans_;  // for the map
  std::vector<SE2> keyframe_motion_;       // predicted motion from the previous keyframe (odometry or matched)
  std::vector<ScanRecord> scans_;
  PoseGraph graph_;
  SparsePoseAdjustment back_end_;
  LoopCloser loop_closer_;
  GraphSlamStats stats_;
  MatchMap local_map_;                 // the recent keyframes' points, rebuilt when a keyframe or the graph changes
  bool local_map_stale_ = true;
  std::optional<SE2> last_odom_;     // odometry pose at the previous scan
  std::optional<SE2> velocity_;      // without odometry: the motion per second between the last two scans
  double last_stamp_ = 0.0;
  double uncertainty_variance_ = 0.0;  // m^2, position variance accumulated since the last loop closure
};

}  // namespace slam2d
