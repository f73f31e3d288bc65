// SPDX-License-Identifier: BSD-3-Clause
// Graph SLAM (slam/graph) on the ACES log of Kuemmerle et al. 2009, the default configuration:
// loops are closed, and the relation error stays under bounds a little above what was measured
// (0.0381 m, 0.341 deg; bench/BENCHMARKS.md has every log), far under Hector's 0.095 m on it.
// And a loop that closes at the end of a log: ACES without odometry cut as the robot comes back,
// about 3.6 m off, to a corridor it mapped 560 s before. Intel and FR079 take 8-11 s
// each and are left to the dataset benchmark, but for Intel's clean bound, FR079 mapped twice (with and without the
// back end's deferral) and, with mixed pixels, twice more (with and without the check of large
// corrections), and for Intel without odometry twice (the check's memory of refused corrections, and
// loops closed onto thin walls seen from their other face).
// And Freiburg campus (carmen-corrected), whose exact odometry graph SLAM must stay near.

#include <gtest/gtest.h>

#include <iostream>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/odometry_chain.hpp"
#include "slam2d/eval/ate.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/registration/odometry_time_offset.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "real_data/real_logs.hpp"
#include "support/graph_configs.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

// The scans of a CARMEN log up to `last_stamp` (with their odometry or without), then finish().
GraphSlam map_log(const std::filesystem::path& log, bool odometry, double last_stamp = 1e300,
                  const GraphSlamConfig& config = {}) {
  GraphSlam slam(config);
  CarmenReader reader(log.string());
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->scan.stamp > last_stamp) continue;
    slam.add_scan(laser->scan, odometry ? std::optional<SE2>(laser->odom_pose) : std::nullopt);
  }
  slam.finish();
  return slam;
}

// ACES with its odometry, default configuration (0.037 m): the reference of the cut run.
const GraphSlam& aces_with_odometry(const std::filesystem::path& data) {
  static const GraphSlam slam = map_log(data / "aces/aces.clf.gz", true);
  return slam;
}

// The last pose of `trajectory` in the frame of its first, against the reference's poses at the
// same stamps (m).
double end_error(const Trajectory& trajectory, const Trajectory& reference) {
  const StampIndex index(reference);
  const auto first = index.nearest(trajectory[0].stamp, 0.001);
  const auto last = index.nearest(trajectory[trajectory.size() - 1].stamp, 0.001);
  if (!first || !last) return 1e9;
  const SE2 estimated = trajectory[0].pose.between(trajectory[trajectory.size() - 1].pose);
  const SE2 expected = reference[*first].pose.between(reference[*last].pose);
  return (estimated.translation() - expected.translation()).norm();
}

// The public log `name`'s scans with `fault` injected (perturb's, seed 1), mapped with their
// odometry: the relation error over all relations (m).
double error_under(const std::filesystem::path& data, const std::string& name, const std::string& fault,
                   const GraphSlamConfig& config) {
  GraphSlam slam(config);
  for (const LaserMessage& laser : test::laser_messages(test::read_log_with_fault(data / name / (name + ".clf.gz"), fault))) {
    slam.add_scan(laser.scan, laser.odom_pose);
  }
  slam.finish();
  return relation_error(slam.trajectory(), read_relations((data / name / (name + ".relations")).string())).translation.mean;
}

// FR079 mapped with a configuration: what the back end's schedule did, and the relation error.
struct Fr079Run {
  GraphSlamStats stats;
  double error = 0.0;  // m, mean translational relation error
};

Fr079Run map_fr079(const std::filesystem::path& data, const GraphSlamConfig& config) {
  const GraphSlam slam = map_log(data / "fr079/fr079.clf.gz", true, 1e300, config);
  const std::vector<Relation> relations = read_relations((data / "fr079/fr079.relations").string());
  return {slam.stats(), relation_error(slam.trajectory(), relations).translation.mean};
}

// The defaults' run, mapped once for the tests below.
const Fr079Run& fr079_defaults(const std::filesystem::path& data) {
  static const Fr079Run run = map_fr079(data, GraphSlamConfig{});
  return run;
}

// The back end's schedule (GraphSlamConfig::defer_agreeing_closures) on FR079, whose robot comes
// back to its rooms and corridors: more than a third of its closures revisit a place closed before
// and agree with the estimate, their optimisations wait, and the relation error stays that of an
// optimisation after every closure (measured: 19 of 33 deferred, 15 optimisations against 33,
// 0.0381 m, and 0.0394 m with Karto's schedule at the tolerance before, 1e-9; over the clean log
// and eight noise seeds of each public log the means moved by +1.4 / +0.2 / -0.8 % for Intel /
// ACES / FR079, docs/methods/graph_slam.md).
TEST(GraphSlamRealData, DefersTheClosuresOfFr079sRevisitsThatAgree) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  GraphSlamConfig every_closure;
  every_closure.defer_agreeing_closures = false;
  const Fr079Run karto = map_fr079(data, every_closure);
  const Fr079Run& deferred = fr079_defaults(data);
  EXPECT_EQ(karto.stats.deferred_optimizations, 0u);
  EXPECT_GT(3 * deferred.stats.deferred_optimizations, deferred.stats.loop_closures);
  EXPECT_LT(deferred.stats.optimizations, 0.7 * static_cast<double>(karto.stats.optimizations));
  EXPECT_LT(deferred.error, 1.1 * karto.error);
  EXPECT_LT(deferred.error, 0.045);  // m
}

// Short cycles optimised over their neighbourhood (GraphSlamConfig::local_reach) on FR079: most of
// its optimisations during the run are of closures whose cycle along the graph is short, they free
// the nodes around it only, and the relation error stays that of whole-graph optimisations
// (measured, `slam2d map` without smoothing: 10 of 15 local, 0.0379 m against 0.0381 m; Intel's
// and FR079's ten passes and the noise seeds of each public log in docs/methods/graph_slam.md).
// Measured without the tracker's calibration: with it (the defaults since 2026-12-07) FR079 closes
// fewer loops during the run (9 optimisations, 3 local), and the comparison is of that run's few.
TEST(GraphSlamRealData, OptimisesFr079sShortCyclesOverTheirNeighbourhood) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  GraphSlamConfig whole_graph = test::graph_without_calibration();
  whole_graph.local_reach = 0.0;
  const Fr079Run whole = map_fr079(data, whole_graph);
  const Fr079Run local = map_fr079(data, test::graph_without_calibration());
  EXPECT_EQ(whole.stats.local_optimizations, 0u);
  EXPECT_GT(2 * local.stats.local_optimizations, local.stats.optimizations);
  EXPECT_LT(local.error, 1.05 * whole.error);
  EXPECT_LT(local.error, 0.045);  // m
  EXPECT_LT(fr079_defaults(data).error, 0.045);
}

// Three glass sectors of 45 deg leave the 180 deg scanner a quarter of its view, and the matches
// slide along what is left. The tracker's odometry prior weighed by the odometry's learnt noise
// (HectorSlamConfig::prior_from_motion_noise, with Hector's Cauchy kernel; the default) holds the
// poses to the good odometry there; the constant weak prior of the defaults before 2026-12-03
// (sigma 0.1 m, a plain Gaussian, with the fixed sequential covariance and odometry edges) does not
// (measured: 0.044 m against 1.00 m over all relations; clean 0.038 m; about 0.2 m since the odometry
// refutes the tracker's matches held back over four map updates, core/match_progress.hpp).
TEST(GraphSlamRealData, APriorWeighedByTheMotionNoiseHoldsGlassOverGoodOdometry) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::string glass = "glass:sectors=3,width=45";
  const GraphSlamConfig fixed = test::graph_with_fixed_tracker_prior();
  EXPECT_LT(error_under(data, "aces", glass, GraphSlamConfig{}), 0.08);
  EXPECT_GT(error_under(data, "aces", glass, fixed), 0.15) << "the fault no longer tests the prior";
}

// Freiburg campus, SLAM-corrected: the odometry of its FLASER lines is the corrected trajectory
// itself, exact, and graph SLAM must stay near it. Its sparse outdoor scans, many of which the map
// cannot explain at their true pose, were turned 5-12 deg a step by the matcher's rotated starts,
// and a false loop closed on the turned map (6.05 m ATE; 0.778 m since a rotated start that
// contradicts the prior must explain the scan, HectorMatcherConfig::rotation_search_min_explained).
// Stamped by index, as the robustness benchmark does: the log's stamps do not increase.
double freiburg_campus_ate(const std::filesystem::path& data, const GraphSlamConfig& config) {
  const test::CorrectedScans campus = test::read_corrected_flaser(data / "carmen-corrected/freiburg-campus-corrected.log.gz");
  GraphSlam slam(config);
  for (const LaserMessage& laser : campus.scans) slam.add_scan(laser.scan, laser.odom_pose);
  slam.finish();
  return absolute_trajectory_error(slam.trajectory(), campus.reference).rmse;
}

TEST(GraphSlamRealData, StaysNearFreiburgCampussExactOdometry) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const double ate = freiburg_campus_ate(data, GraphSlamConfig{});
  std::cout << "[ measured ] freiburg-campus, exact odometry: graph " << ate << " m ATE\n";
  EXPECT_LT(ate, 1.5);
  GraphSlamConfig lower_cost_wins;
  lower_cost_wins.tracking.matcher.rotation_search_min_explained = 0.0;
  EXPECT_GT(freiburg_campus_ate(data, lower_cost_wins), 3.0) << "the log no longer tests the rotated starts";
}

// FR079 at one scan a second: at t = 1000 s the wheel odometry misses 0.45 rad of a 0.62 rad turn,
// all in one step. The prior of constant weight kept that heading (0.40 m over all relations, the
// end 7 m off); the weighed prior's Cauchy kernel lets the retry over every heading after the
// poor fit win (`slam2d map`, smoothed: 0.048 m; the clean log 0.039 m).
TEST(GraphSlamRealData, TakesBackAnOdometrySlipInOneStepAtOneHertz) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  EXPECT_LT(error_under(data, "fr079", "scan-rate:hz=1", GraphSlamConfig{}), 0.07);
  EXPECT_GT(error_under(data, "fr079", "scan-rate:hz=1", test::graph_with_fixed_tracker_prior()), 0.2)
      << "the fault no longer tests the weighed prior";
}

// Intel with its odometry 0.6 s ahead of the laser (`odom-shift:by=0.6`), the offset estimated and
// compensated as `slam2d map` does. Intel's logger stamped scans as it read them: after a pause of
// about 2 s come ten or more scans stamped 1 ms apart that were taken during the pause. Shifted
// along those stamps, the odometry freezes over a burst and puts its motion on the scan after the
// pause (at t = 2429 s: 1.3 rad where the robot turned 0.1). The tracker's match from there fit
// poorly, and its retry over every heading found the mirror heading of a corridor (0.92 m over all
// relations, 180 deg off); a trusted increment's retry turns a quarter turn at most (0.072 m with
// `slam2d map`), and an increment over a pause is confirmed against the last pose
// (OdometryCheck::confirm: 0.020 m; the clean log 0.020 m).
TEST(GraphSlamRealData, IsNotTurnedAroundWhereItsOdometryIsOutOfStepInTime) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<Relation> relations = read_relations((data / "intel/intel.relations").string());
  const test::ScansOutOfStep out_of_step = test::read_scans_out_of_step(data / "intel/intel.clf.gz", 0.6);
  EXPECT_NEAR(out_of_step.estimate, 0.6, 0.05);
  const std::vector<LaserMessage>& scans = out_of_step.scans;
  const auto error = [&](const GraphSlamConfig& config) {
    GraphSlam slam(config);
    for (const LaserMessage& laser : scans) slam.add_scan(laser.scan, laser.odom_pose);
    slam.finish();
    return relation_error(slam.trajectory(), relations);
  };
  const RelationErrorResult confirmed = error(GraphSlamConfig{});
  std::cout << "[ measured ] intel, odometry 0.6 s ahead: graph " << confirmed.translation.mean << " m, worst "
            << confirmed.rotation_deg.max << " deg\n";
  EXPECT_LT(confirmed.translation.mean, 0.03);
  EXPECT_LT(confirmed.rotation_deg.max, 10.0);
  GraphSlamConfig unconfirmed;
  unconfirmed.tracking.odometry_guard.confirm_pause = 0.0;
  EXPECT_GT(error(unconfirmed).translation.mean, 0.05) << "the log no longer tests the confirmation";
}

// FR079 with half its beams mixed pixels (`mixed-pixels:p=0.5`, seed 1): at keyframe 1576 the large
// window matches a room 2.5 m off, a keyframe before it matches the same room the same wrong way,
// and the confirmed large correction went in without the kernel; four of the 23 closures that agreed
// with the graph gave way (0.34 m over all relations; the clean log 0.038 m). Four refuted against
// the pair's two edges: it is refused (GraphSlamConfig::check_large_closures; `slam2d map` 0.037 m).
// Measured without the tracker's calibration, whose run (the defaults since 2026-12-07) does not
// match that room and stays near the clean one either way (0.039 m unchecked).
TEST(GraphSlamRealData, RefusesALargeCorrectionTheLoopsItHoldsRefute) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::string mixed = "mixed-pixels:p=0.5";
  GraphSlamConfig unchecked = test::graph_without_calibration();
  unchecked.check_large_closures = false;
  EXPECT_LT(error_under(data, "fr079", mixed, GraphSlamConfig{}), 0.045);
  EXPECT_LT(error_under(data, "fr079", mixed, test::graph_without_calibration()), 0.045);
  EXPECT_GT(error_under(data, "fr079", mixed, unchecked), 0.2) << "the fault no longer tests the check";
}

// Intel without odometry, 1 cm range noise (seed 6): the tracker drifts 2.3 m along the way back,
// and the large correction that takes it back (found at keyframe 2896, 2.3 m, and again at 2904,
// 2944, ...) refutes five closures of the stretch before, which the stiff sequential chain lets give
// way first. Alone it was refused again and again (0.16 m over all relations with `slam2d map`);
// remembered, the refused corrections that agree with a later one count with it, and three go in
// (0.027 m; without the check 0.028 m).
TEST(GraphSlamRealData, LetsLargeCorrectionsThatAgreeOutvoteTheClosuresTheyRefute) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  GraphSlam slam;
  for (const LaserMessage& laser :
       test::laser_messages(test::read_log_with_fault(data / "intel/intel.clf.gz", "range-noise:sigma=0.01", 6))) {
    slam.add_scan(laser.scan, std::nullopt);
  }
  slam.finish();
  const double error =
      relation_error(slam.trajectory(), read_relations((data / "intel/intel.relations").string())).translation.mean;
  EXPECT_LT(error, 0.035);
  EXPECT_GE(slam.stats().large_closures, 1u);
}

// Intel without odometry: the map holds the corridor's face of a room's thin walls (the first
// scans'), and the last scans, back in the room, see their other face. Those loop matches fit the
// map from behind and lie near the graph's estimate; refused like a corner fitted from beyond it
// (the hospital world's false closure, 3.4 m off), they cost 0.0200 -> 0.0356 m over all
// relations, the final loop back to the start among them. Only large corrections seen from behind
// are refused (measured: 0.0203 m).
TEST(GraphSlamRealData, ClosesIntelsLoopsOntoThinWallsSeenFromTheirOtherFace) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const GraphSlam slam = map_log(data / "intel/intel.clf.gz", false);
  const double error =
      relation_error(slam.trajectory(), read_relations((data / "intel/intel.relations").string())).translation.mean;
  std::cout << "[ measured ] intel without odometry: graph " << error << " m\n";
  EXPECT_LT(error, 0.025);
}

TEST(GraphSlamRealData, ClosesTheLoopsOfAces) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const GraphSlam& slam = aces_with_odometry(data);
  EXPECT_GT(slam.stats().loop_closures, 5u);
  EXPECT_LT(slam.stats().sequential_failures, 20u);
  const RelationErrorResult error =
      relation_error(slam.trajectory(), read_relations((data / "aces/aces.relations").string()));
  EXPECT_EQ(error.missing, 0u);
  EXPECT_EQ(error.relations, 1279u);
  EXPECT_LT(error.translation.mean, 0.042);       // m
  EXPECT_LT(error.rotation_deg.mean, 0.40);       // deg
  // The odometry enters once, through the tracker's weighed prior (no odometry edge counts it
  // again), whose noise model learnt from the matches of most scans and kept its scales inside
  // their bounds.
  EXPECT_EQ(slam.stats().odometry_edges, 0u);
  EXPECT_GT(slam.odometry_noise().observations(), 5000u);
  EXPECT_LT(slam.odometry_noise().translation_scale(), slam.odometry_noise().config().max_scale);
  EXPECT_GT(slam.odometry_noise().translation_scale(), slam.odometry_noise().config().min_scale);
}

// ACES's wheel odometry has no systematic error to speak of (against graph SLAM's closed
// trajectory over the whole log: distance scale 0.994, turn scale 1.004, drift -0.005 rad/m), but
// the tracker's matches, whose own errors bend with its map, suggest one (a fit over 1000 stretches
// finds drift -0.004 rad/m and scales within 1 % of one). Corrected, that cost ACES a loop
// (0.041 m over all relations). The tracker corrects only what stands out of the fit's
// uncertainty (OdometryCalibrationConfig::significance): on ACES nothing, at any point of the run
// (the trajectory is that of no calibration, 0.0379 m), where Intel's 0.06 rad/m drift is
// corrected nearly whole (HectorRealDataTracker.TheWeighedPriorsCalibrationFindsTheIntelOdometrysSystematicError).
TEST(GraphSlamRealData, CorrectsNoSystematicErrorInAcessOdometry) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const OdometryCalibration* calibration = aces_with_odometry(data).odometry_calibration();
  ASSERT_NE(calibration, nullptr);
  EXPECT_GT(calibration->observations(), 500u);
  EXPECT_EQ(calibration->translation_scale(), 1.0);
  EXPECT_EQ(calibration->rotation_scale(), 1.0);
  EXPECT_EQ(calibration->drift_per_metre(), 0.0);
}

// Intel, the defaults: the bound issue 40 keeps (0.0197 m over all relations; 0.0204 m before the
// tracker corrected the odometry's systematic error, 0.0177 m with it).
TEST(GraphSlamRealData, MapsIntelWithinItsCleanBound) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const GraphSlam slam = map_log(data / "intel/intel.clf.gz", true);
  const double error =
      relation_error(slam.trajectory(), read_relations((data / "intel/intel.relations").string())).translation.mean;
  EXPECT_LT(error, 0.0197);
}

// Without odometry the tracker drifts 3.6 m around ACES's second large loop; the log is cut at
// 1045 s, a few seconds after the robot is back in the corridor of 489 s. The loop must close
// there, a large correction confirmed by a second keyframe (the code before left the end 3.56 m
// off the reference, measured). The cut was chosen when only finish()'s search from the last
// keyframes closed it; since the loop match's point-to-line refinement takes a cycle of its pairs
// for its end (PoseCycle), the keyframes of 1039.5 s and 1041.2 s close and confirm it before
// the end, and a cut before 1041.2 s leaves it unconfirmed (3.5 m off). finish()'s search alone
// is tested on the simulated late loop (tests/slam/graph/long_loop_test.cpp).
// 198 s of the scans missing from t = 300 s (the held-out hospital log has such a gap), the
// wheel odometry kept. Intel's odometry is 17 m and 1.5 rad off across the gap: the tracker, pulled
// onto its old map at the wrong place, left everything after the gap there (3.2 m over all
// relations). Across a gap the tracker starts a new map, and the loop closer searches as far as
// the odometry's drift measured before the gap reaches (GraphSlamConfig::gap): 0.017 m.
// ACES's odometry is 1.7 m and 0.1 rad off there, its relocalization was right already, and stays
// right (0.040 m; the clean log 0.038 m). FR079's is 17 m and 1 rad off, and the chain nearest the
// estimate holds an office 17 m along the corridor that matches as well as the right one: with one
// chain per global search that one won (2.0 m), with four the right one does (0.038 m).
TEST(GraphSlamRealData, FindsItsPlaceAgainAfterAGapInTheScans) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::string gap = "scan-gap:every=100000,start=300,duration=198";
  GraphSlamConfig without;
  without.gap.seconds = 1e9;
  EXPECT_LT(error_under(data, "intel", gap, GraphSlamConfig{}), 0.03);
  EXPECT_GT(error_under(data, "intel", gap, without), 1.0) << "the gap no longer tests the handling";
  EXPECT_LT(error_under(data, "aces", gap, GraphSlamConfig{}), 0.045);
  EXPECT_LT(error_under(data, "fr079", gap, GraphSlamConfig{}), 0.045);
  // FR079's alias, measured without the tracker's calibration (with it, the defaults since
  // 2026-12-07, the nearest chain is the right one: 0.038 m with one chain).
  GraphSlamConfig nearest_chain = test::graph_without_calibration();
  nearest_chain.loop_closure.large.max_global_chains = 1;
  EXPECT_LT(error_under(data, "fr079", gap, test::graph_without_calibration()), 0.045);
  EXPECT_GT(error_under(data, "fr079", gap, nearest_chain), 0.5) << "the alias no longer tests the chains searched";
}

// A log like the held-out hospital log: a scan about every 0.6 s, neighbouring beams alternating
// near and far, and 198 s of scans missing at 300 s. On ACES a confirmed pair of large closures
// put the keyframes after the gap 30 m along a corridor (1.01 m over all relations, 32 m across
// the gap against the odometry's 14.6 m); the map before the gap contradicts them there (its free
// space under their walls), and they are refused (`loop_closure.large.max_contradiction`;
// measured through `slam2d map`: 0.057 m).
TEST(GraphSlamRealData, RefusesALargeClosureTheOldMapsFreeSpaceContradicts) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const auto error_with = [&](const GraphSlamConfig& config) {
    GraphSlam slam(config);
    const std::vector<std::string> faults{"scan-rate:hz=1.7", "mixed-pixels:p=1,alternate=6",
                                          "scan-gap:every=100000,start=300,duration=198"};
    for (const LaserMessage& laser : test::laser_messages(test::read_log_with_faults(data / "aces/aces.clf.gz", faults))) {
      slam.add_scan(laser.scan, laser.odom_pose);
    }
    slam.finish();
    return std::pair{relation_error(slam.trajectory(), read_relations((data / "aces/aces.relations").string())).translation.mean,
                     slam.stats().contradicted_large_closures};
  };
  const auto [error, refused] = error_with(GraphSlamConfig{});
  EXPECT_LT(error, 0.08);
  EXPECT_GE(refused, 1u);
  GraphSlamConfig unchecked;
  unchecked.loop_closure.large.max_contradiction = 1.0;
  EXPECT_GT(error_with(unchecked).first, 0.5) << "the log no longer tests the check";
}

TEST(GraphSlamRealData, ClosesALoopAtTheEndOfACutLog) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  GraphSlamConfig immediate;
  immediate.loop_closure.delayed = false;
  const GraphSlam cut = map_log(data / "aces/aces.clf.gz", false, 1045.0, immediate);
  EXPECT_GE(cut.stats().large_closures, 1u);
  EXPECT_LT(end_error(cut.trajectory(), aces_with_odometry(data).trajectory()), 1.5);  // m (0.91 measured)
  const GraphSlam delayed = map_log(data / "aces/aces.clf.gz", false, 1045.0);
  EXPECT_GE(delayed.stats().large_closures, 1u);
  EXPECT_LT(end_error(delayed.trajectory(), aces_with_odometry(data).trajectory()), 1.5);  // m (0.43 measured)
}

}  // namespace
}  // namespace slam2d
