// SPDX-License-Identifier: BSD-3-Clause
// Fault injection (sim/fault_injection.hpp) on a simulated office run: each fault changes what it
// says and nothing else (stall windows, removed lines, re-integrated odometry against closed
// forms, every third scan), seeds give identical or different logs, bad specs are refused, and
// geometry faults read back through CarmenReader with the kept beams' original angles.

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry_chain.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/sim/fault_injection.hpp"
#include "support/simulated_office.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using Messages = std::vector<SensorMessage>;
constexpr double kPi = std::numbers::pi;

// 150 s of the office: ODOM at 20 Hz, FLASER + TRUEPOS at 10 Hz, stamps from 0.
const Messages& office() { return test::simulated_office(150.0, 3).messages; }

Messages perturbed(const std::string& spec, std::uint64_t seed = 1, Messages messages = office()) {
  apply_faults({parse_fault(spec)}, messages, seed);
  return messages;
}

FaultReport report_of(const std::string& spec, Messages& messages, std::uint64_t seed = 1) {
  return apply_faults({parse_fault(spec)}, messages, seed).front();
}

double change(const FaultReport& report, const std::string& key) {
  for (const auto& [name, value] : report.changes) {
    if (name == key) return value;
  }
  ADD_FAILURE() << "no change '" << key << "' in " << report.spec;
  return -1.0;
}

template <typename T>
std::vector<T> of_type(const Messages& messages) {
  std::vector<T> result;
  for (const SensorMessage& m : messages) {
    if (const T* typed = std::get_if<T>(&m)) result.push_back(*typed);
  }
  return result;
}

// Window m of "every=20,duration=1.2" from t0 = 0 (the office run's first stamp): [20 (m + 1), 20 (m + 1) + 1.2).
bool in_window(double stamp) {
  const double since = stamp - 20.0;
  return since >= 0.0 && since - 20.0 * std::floor(since / 20.0) < 1.2;
}

double path_length(const std::vector<SE2>& poses) {
  double length = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i) length += (poses[i].translation() - poses[i - 1].translation()).norm();
  return length;
}

std::vector<SE2> laser_odometry(const Messages& messages) {
  std::vector<SE2> poses;
  for (const LaserMessage& laser : of_type<LaserMessage>(messages)) poses.push_back(laser.odom_pose);
  return poses;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// ---------------------------------------------------------------------------------------------
// Specs.

TEST(FaultSpec, DefaultsAndCanonicalSpecs) {
  EXPECT_EQ(fault_spec(parse_fault("stall")), "stall:every=60,start=60,duration=1.2");
  EXPECT_EQ(fault_spec(parse_fault("stall:every=30")), "stall:every=30,start=30,duration=1.2");  // start = every
  EXPECT_EQ(fault_spec(parse_fault("stall:duration=3,start=0")), "stall:every=60,start=0,duration=3");
  EXPECT_EQ(fault_spec(parse_fault("wheel-scale")), "wheel-scale:translation=1.05,rotation=1");
  EXPECT_EQ(fault_spec(parse_fault("range-max:max=5.6")), "range-max:max=5.6");
  EXPECT_EQ(fault_spec(parse_fault("repeat:times=10")), "repeat:times=10");
  EXPECT_EQ(std::get<BeamsFault>(parse_fault("beams:k=3")).k, 3u);
  EXPECT_EQ(std::get<HeadingDriftFault>(parse_fault("heading-drift:rate=-0.25")).rate_deg_per_m, -0.25);
  for (const std::string& kind : fault_kinds()) {  // every kind parses with its defaults and round-trips
    const std::string spec = fault_spec(parse_fault(kind));
    EXPECT_EQ(spec.rfind(kind + ":", 0), 0u) << spec;
    EXPECT_EQ(fault_spec(parse_fault(spec)), spec);
  }
  EXPECT_EQ(fault_kinds().size(), 24u);
  EXPECT_EQ(fault_spec(parse_fault("odom-shift")), "odom-shift:by=0.6");
  EXPECT_EQ(fault_spec(parse_fault("odom-shift:by=-0.3")), "odom-shift:by=-0.3");
  EXPECT_EQ(fault_spec(parse_fault("scan-rate")), "scan-rate:hz=1");
  EXPECT_EQ(fault_spec(parse_fault("spurious-far:p=0.1")), "spurious-far:p=0.1,min=20,max=50");
  EXPECT_EQ(fault_spec(parse_fault("mixed-pixels:alternate=6")), "mixed-pixels:p=0.5,jump=0.5,alternate=6");
  EXPECT_EQ(fault_spec(parse_fault("glass")), "glass:sectors=2,width=30");
  EXPECT_EQ(fault_spec(parse_fault("laser-noise:bearing=1")), "laser-noise:sigma=0.05,bearing=1");
  EXPECT_EQ(fault_spec(parse_fault("odom-noise")), "odom-noise:translation=0.05,heading=0.02,rotation=0.05");
  EXPECT_EQ(fault_spec(parse_fault("odom-reset:every=30")), "odom-reset:every=30,start=30");
}

TEST(FaultSpec, BadSpecsAreRefusedWithAReason) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"wobble", "unknown fault kind 'wobble'"},
      {"wobble:x", "unknown fault kind 'wobble' (kinds: stall, odom-gap, odom-reset, wheel-scale, heading-drift, odom-noise, odom-shift, scan-gap,"},
      {"odom-shift:by=5.5", "by=5.5 is out of range [-5, 5]"},
      {"scan-rate:hz=0", "hz=0 is out of range (0, 1000]"},
      {"spurious-far:min=50,max=20", "min must be less than max"},
      {"mixed-pixels:jump=0", "jump=0 is out of range (0, inf)"},
      {"mixed-pixels:alternate=101", "alternate must be at most 100"},
      {"glass:sectors=0", "sectors=0 must be >= 1"},
      {"glass:width=400", "width=400 is out of range (0, 360]"},
      {"laser-noise:bearing=-1", "bearing=-1 is out of range [0, 90]"},
      {"odom-noise:translation=-1", "translation=-1 is out of range [0, 10]"},
      {"odom-reset:every=0", "every=0 is out of range (0, inf)"},
      {"stall:every=60,lenght=2", "unknown key 'lenght' for stall (keys: every, start, duration)"},
      {"stall:every=abc", "every is not a number: 'abc'"},
      {"stall:every=-5", "every=-5 is out of range (0, inf)"},
      {"stall:every=10,duration=10", "duration must be shorter than every"},
      {"stall:every=1,every=2", "key 'every' given twice"},
      {"stall:every", "expected key=value, got 'every'"},
      {"stall:every=60,", "expected key=value, got ''"},
      {"decimate:k=2.5", "k is not an integer: '2.5'"},
      {"decimate:k=0", "k=0 must be >= 1"},
      {"duplicate:p=1.5", "p=1.5 is out of range [0, 1]"},
      {"jitter:sigma=nan", "sigma is not a number: 'nan'"},
      {"spurious-short:min=0.5,max=0.1", "min must be less than max"},
      {"fov:deg=0", "deg=0 is out of range (0, 360]"},
      {"wheel-scale:translation=0", "translation=0 is out of range (0, 10]"},
  };
  for (const auto& [spec, reason] : cases) {
    try {
      parse_fault(spec);
      ADD_FAILURE() << "accepted " << spec;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("--fault '" + spec + "': ", 0), 0u) << what;
      EXPECT_NE(what.find(reason), std::string::npos) << what;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Odometry faults.

TEST(FaultInjection, StallHoldsTheOdometryInEachWindowThenCatchesUp) {
  Messages messages = office();
  const FaultReport report = report_of("stall:every=20,duration=1.2", messages);
  const std::vector<LaserMessage> before = of_type<LaserMessage>(office());
  const std::vector<LaserMessage> after = of_type<LaserMessage>(messages);
  ASSERT_EQ(before.size(), after.size());
  std::size_t frozen = 0;
  for (std::size_t i = 1; i < after.size(); ++i) {
    const bool inside = in_window(after[i].scan.stamp);
    if (!inside) {
      EXPECT_EQ(after[i].odom_pose, before[i].odom_pose) << i;  // untouched, and the true pose right after
      continue;
    }
    // Held: the pose of the last scan before the window (TRUEPOS at the same stamp shares it).
    std::size_t last_outside = i;
    while (in_window(before[last_outside].scan.stamp)) --last_outside;
    EXPECT_EQ(after[i].odom_pose, before[last_outside].odom_pose) << i;
    EXPECT_EQ(after[i].laser_pose, after[i].odom_pose) << i;  // the repeated triple follows
    frozen += after[i].odom_pose == before[i].odom_pose ? 0 : 1;
    EXPECT_EQ(after[i].scan.ranges, before[i].scan.ranges);
  }
  EXPECT_EQ(change(report, "stalls"), 7.0);  // windows at 20, 40, ..., 140 s
  EXPECT_GE(frozen, 7u * 12u * 9u / 10u);     // 12 scans a window, the robot moving almost always
  // The catch-up: from the held pose to the true one at the first scan after each window.
  double largest_jump = 0.0;
  for (std::size_t i = 1; i < after.size(); ++i) {
    if (in_window(after[i - 1].scan.stamp) && !in_window(after[i].scan.stamp)) {
      largest_jump = std::max(largest_jump, (after[i].odom_pose.translation() - after[i - 1].odom_pose.translation()).norm());
    }
  }
  EXPECT_NEAR(change(report, "max_catch_up_m"), largest_jump, 1e-12);
  EXPECT_GT(largest_jump, 0.6);  // about 1.3 s at 0.6 m/s
  // ODOM lines are frozen too, and kept.
  const std::vector<OdometryMessage> odom_before = of_type<OdometryMessage>(office());
  const std::vector<OdometryMessage> odom_after = of_type<OdometryMessage>(messages);
  ASSERT_EQ(odom_before.size(), odom_after.size());
  for (std::size_t i = 1; i < odom_after.size(); ++i) {
    if (in_window(odom_after[i].reading.stamp) && in_window(odom_after[i - 1].reading.stamp)) {
      EXPECT_EQ(odom_after[i].reading.pose, odom_after[i - 1].reading.pose) << i;
    } else if (!in_window(odom_after[i].reading.stamp)) {
      EXPECT_EQ(odom_after[i].reading.pose, odom_before[i].reading.pose) << i;
    }
    EXPECT_EQ(odom_after[i].reading.tv, odom_before[i].reading.tv);
  }
}

TEST(FaultInjection, OdomGapRemovesOdomLinesAndHoldsTheLaserOdometry) {
  Messages messages = office();
  const FaultReport report = report_of("odom-gap:every=20,duration=1.2", messages);
  std::size_t removed = 0;
  for (const OdometryMessage& odom : of_type<OdometryMessage>(office())) removed += in_window(odom.reading.stamp) ? 1 : 0;
  for (const OdometryMessage& odom : of_type<OdometryMessage>(messages)) EXPECT_FALSE(in_window(odom.reading.stamp));
  EXPECT_EQ(of_type<OdometryMessage>(messages).size() + removed, of_type<OdometryMessage>(office()).size());
  EXPECT_EQ(change(report, "odom_lines_removed"), static_cast<double>(removed));
  EXPECT_GE(removed, 7u * 24u);
  // The lasers are all there, their odometry held as by stall.
  Messages stalled = perturbed("stall:every=20,duration=1.2");
  EXPECT_EQ(laser_odometry(messages), laser_odometry(stalled));
}

// A restart every 20 s from 20 s: each chain's first pose at or after a restart is the origin,
// later ones relative to it; the robot's motion between any two poses of one period is kept.
TEST(FaultInjection, OdomResetRestartsEachChainFromTheOrigin) {
  Messages messages = office();
  const FaultReport report = report_of("odom-reset:every=20", messages);
  EXPECT_EQ(change(report, "restarts"), 7.0);  // at 20, 40, ..., 140 s
  const std::vector<LaserMessage> before = of_type<LaserMessage>(office());
  const std::vector<LaserMessage> after = of_type<LaserMessage>(messages);
  ASSERT_EQ(before.size(), after.size());
  const auto period = [](double stamp) { return stamp < 20.0 ? -1L : static_cast<long>(std::floor((stamp - 20.0) / 20.0)); };
  std::size_t origins = 0;
  for (std::size_t i = 1; i < after.size(); ++i) {
    const double t = after[i].scan.stamp;
    if (period(t) < 0) {
      EXPECT_EQ(after[i].odom_pose, before[i].odom_pose) << t;  // before the first restart: as logged
    } else if (period(t) != period(after[i - 1].scan.stamp)) {
      EXPECT_NEAR(after[i].odom_pose.vector().norm(), 0.0, 1e-12) << t;  // the restart's first pose
      ++origins;
    } else {
      const SE2 moved = after[i - 1].odom_pose.between(after[i].odom_pose);
      const SE2 truth = before[i - 1].odom_pose.between(before[i].odom_pose);
      EXPECT_NEAR((moved.vector() - truth.vector()).norm(), 0.0, 1e-9) << t;
    }
  }
  EXPECT_EQ(origins, 7u);
  EXPECT_GT(change(report, "max_restart_jump_m"), 1.0);
}

TEST(FaultInjection, WheelScaleOfOneChangesNothingBitForBit) {
  Messages messages = office();
  const FaultReport report = report_of("wheel-scale:translation=1,rotation=1", messages);
  EXPECT_EQ(change(report, "odometry_poses_changed"), 0.0);
  EXPECT_EQ(laser_odometry(messages), laser_odometry(office()));
  // A factor next to 1 moves poses by next to nothing: the rule is continuous at 1.
  const Messages near_one = perturbed("wheel-scale:translation=1.000000001");
  const std::vector<SE2> a = laser_odometry(near_one), b = laser_odometry(office());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].is_approx(b[i], 1e-6)) << i;
}

TEST(FaultInjection, WheelScaleStretchesThePathAboutTheFirstPose) {
  const Messages messages = perturbed("wheel-scale:translation=1.05");
  const SE2 anchor = std::get<OdometryMessage>(office().front()).reading.pose;
  const std::vector<SE2> before = laser_odometry(office()), after = laser_odometry(messages);
  EXPECT_NEAR(path_length(after) / path_length(before), 1.05, 1e-9);
  for (std::size_t i = 0; i < after.size(); ++i) {  // closed form: p' = p0 + 1.05 (p - p0), same heading
    const Eigen::Vector2d expected = anchor.translation() + 1.05 * (before[i].translation() - anchor.translation());
    EXPECT_NEAR((after[i].translation() - expected).norm(), 0.0, 1e-9) << i;
    EXPECT_NEAR(angle_difference(after[i].theta(), before[i].theta()), 0.0, 1e-9) << i;
  }
  // The ODOM chain gets the same closed form: both chains stay one odometry.
  const auto odom_before = of_type<OdometryMessage>(office()), odom_after = of_type<OdometryMessage>(messages);
  for (std::size_t i = 0; i < odom_after.size(); ++i) {
    const Eigen::Vector2d expected = anchor.translation() + 1.05 * (odom_before[i].reading.pose.translation() - anchor.translation());
    EXPECT_NEAR((odom_after[i].reading.pose.translation() - expected).norm(), 0.0, 1e-9) << i;
  }
}

// Total heading change along a pose sequence, unwrapped.
double turned(const std::vector<SE2>& poses) {
  double total = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i) total += angle_difference(poses[i].theta(), poses[i - 1].theta());
  return total;
}

// The rotation of every increment along a pose sequence.
std::vector<double> turns(const std::vector<SE2>& poses) {
  std::vector<double> result;
  for (std::size_t i = 1; i < poses.size(); ++i) result.push_back(poses[i - 1].between(poses[i]).theta());
  return result;
}

TEST(FaultInjection, RotationScaleAndHeadingDriftTurnAsStated) {
  const std::vector<SE2> before = laser_odometry(office());
  const std::vector<double> turns_before = turns(before);
  const std::vector<double> turns_after = turns(laser_odometry(perturbed("wheel-scale:translation=1,rotation=1.1")));
  double turned_abs = 0.0;
  for (std::size_t i = 0; i < turns_before.size(); ++i) {
    EXPECT_NEAR(turns_after[i], 1.1 * turns_before[i], 1e-9) << i;
    turned_abs += std::abs(turns_before[i]);
  }
  EXPECT_GT(turned_abs, 2.0 * kPi);
  const double turned_before = turned(before);

  // Drift: rate x (signed forward travel of each increment), here 1 deg/m.
  double forward = 0.0;
  for (std::size_t i = 1; i < before.size(); ++i) forward += before[i - 1].between(before[i]).x();
  const std::vector<SE2> drifted = laser_odometry(perturbed("heading-drift:rate=1"));
  EXPECT_NEAR(turned(drifted) - turned_before, deg_to_rad(1.0) * forward, 1e-6);
  EXPECT_GT(forward, 50.0);
  // Laser and ODOM chains agree where they sample the same instant (an ODOM at every scan's stamp).
  const Messages drifted_log = perturbed("heading-drift:rate=1");
  const auto lasers = of_type<LaserMessage>(drifted_log);
  const auto odoms = of_type<OdometryMessage>(drifted_log);
  std::size_t compared = 0;
  for (const LaserMessage& laser : lasers) {
    const auto odom = std::find_if(odoms.begin(), odoms.end(), [&](const OdometryMessage& o) {
      return std::abs(o.reading.stamp - laser.scan.stamp) < 1e-9;
    });
    if (odom == odoms.end()) continue;
    EXPECT_TRUE(odom->reading.pose.is_approx(laser.odom_pose, 0.01)) << laser.scan.stamp;
    ++compared;
  }
  EXPECT_GT(compared, lasers.size() / 2);
}

// Random odometry error: zero changes nothing; the error after a stretch of driving has the stated
// spread over seeds (a random walk: sigma sqrt(L)), whatever the sampling; standing still gets
// none; both chains get the same error; the same seed gives the same log.
TEST(FaultInjection, OdomNoiseIsARandomWalkInTheMotion) {
  EXPECT_EQ(laser_odometry(perturbed("odom-noise:translation=0,heading=0,rotation=0")), laser_odometry(office()));
  const std::vector<SE2> before = laser_odometry(office());
  const double length = path_length(before);
  ASSERT_GT(length, 50.0);
  // Along-track only: the path length changes by W_t(L), spread translation * sqrt(L) over seeds;
  // the headings stay as logged.
  double sum = 0.0, sum_squares = 0.0;
  constexpr int kSeeds = 200;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const std::vector<SE2> after = laser_odometry(perturbed("odom-noise:translation=0.1,heading=0,rotation=0", seed));
    ASSERT_EQ(after.size(), before.size());
    // signed: the along-track error of each increment adds up (every increment moves forward here)
    double signed_length = 0.0;
    for (std::size_t i = 1; i < after.size(); ++i) {
      const SE2 a = after[i - 1].between(after[i]), b = before[i - 1].between(before[i]);
      signed_length += b.translation().norm() > 0.0 ? a.translation().dot(b.translation()) / b.translation().norm() : 0.0;
      EXPECT_NEAR(a.theta(), b.theta(), 1e-9);
    }
    const double error = signed_length - length;
    sum += error;
    sum_squares += error * error;
  }
  const double mean = sum / kSeeds, sigma = std::sqrt(sum_squares / kSeeds - mean * mean);
  const double expected = 0.1 * std::sqrt(length);
  EXPECT_NEAR(sigma, expected, 0.15 * expected);  // 200 draws: the spread's own error is 5 %
  EXPECT_NEAR(mean, 0.0, 4.0 * expected / std::sqrt(kSeeds));
  // Heading from turning: total heading error W_r(sum |dtheta|), spread rotation * sqrt(turned).
  double turned_abs = 0.0;
  for (const double turn : turns(before)) turned_abs += std::abs(turn);
  sum = sum_squares = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const double error = turned(laser_odometry(perturbed("odom-noise:translation=0,heading=0,rotation=0.05", seed))) - turned(before);
    sum += error;
    sum_squares += error * error;
  }
  const double turn_sigma = std::sqrt(sum_squares / kSeeds - (sum / kSeeds) * (sum / kSeeds));
  EXPECT_NEAR(turn_sigma, 0.05 * std::sqrt(turned_abs), 0.15 * 0.05 * std::sqrt(turned_abs));
  // Standing still gets no error: a robot that stops (laser lines 50-79 at one pose) stays put.
  Messages stopping = office();
  std::size_t k = 0;
  for (SensorMessage& message : stopping) {  // TRUEPOS lines belong to the laser chain too
    if (auto* truth = std::get_if<TruePoseMessage>(&message); truth != nullptr && k > 50 && k < 80) truth->odom_pose = before[50];
    auto* laser = std::get_if<LaserMessage>(&message);
    if (laser == nullptr) continue;
    if (k >= 50 && k < 80) laser->odom_pose = laser->laser_pose = before[50];
    ++k;
  }
  const std::vector<SE2> stopped = laser_odometry(perturbed("odom-noise:translation=0.2,heading=0.1,rotation=0.2", 1, stopping));
  EXPECT_FALSE(stopped[50] == before[50]);  // the noise before the stop moved it
  for (std::size_t i = 51; i < 80; ++i) EXPECT_TRUE(stopped[i] == stopped[50]) << i;
  const std::vector<SE2> noisy = laser_odometry(perturbed("odom-noise:translation=0.2,heading=0.1,rotation=0.2"));
  // The same seed gives the same log; another seed another.
  EXPECT_EQ(noisy, laser_odometry(perturbed("odom-noise:translation=0.2,heading=0.1,rotation=0.2")));
  EXPECT_NE(noisy, laser_odometry(perturbed("odom-noise:translation=0.2,heading=0.1,rotation=0.2", 2)));
  // Laser and ODOM chains agree where they sample the same instant.
  const Messages log = perturbed("odom-noise:translation=0.2,heading=0.1,rotation=0.2");
  const auto lasers = of_type<LaserMessage>(log);
  const auto odoms = of_type<OdometryMessage>(log);
  std::size_t compared = 0;
  double largest_change = 0.0;
  for (std::size_t k = 0; k < lasers.size(); ++k) {
    const LaserMessage& laser = lasers[k];
    largest_change = std::max(largest_change, (laser.odom_pose.translation() - before[k].translation()).norm());
    const auto odom = std::find_if(odoms.begin(), odoms.end(), [&](const OdometryMessage& o) {
      return std::abs(o.reading.stamp - laser.scan.stamp) < 1e-9;
    });
    if (odom == odoms.end()) continue;
    EXPECT_TRUE(odom->reading.pose.is_approx(laser.odom_pose, 0.02)) << laser.scan.stamp;
    ++compared;
  }
  EXPECT_GT(compared, lasers.size() / 2);
  EXPECT_GT(largest_change, 0.5);  // the noise is not negligible against the tolerance above
}

// ---------------------------------------------------------------------------------------------
// Timing faults.

TEST(FaultInjection, ScanGapRemovesOnlyTheLaserLinesInTheWindows) {
  Messages messages = office();
  const FaultReport report = report_of("scan-gap:every=20,duration=1.2", messages);
  std::vector<double> expected;
  for (const LaserMessage& laser : of_type<LaserMessage>(office())) {
    if (!in_window(laser.scan.stamp)) expected.push_back(laser.scan.stamp);
  }
  std::vector<double> kept;
  for (const LaserMessage& laser : of_type<LaserMessage>(messages)) kept.push_back(laser.scan.stamp);
  EXPECT_EQ(kept, expected);
  EXPECT_EQ(change(report, "laser_lines_removed"), static_cast<double>(of_type<LaserMessage>(office()).size() - kept.size()));
  EXPECT_EQ(change(report, "gaps"), 7.0);
  EXPECT_EQ(of_type<OdometryMessage>(messages).size(), of_type<OdometryMessage>(office()).size());
}

TEST(FaultInjection, DecimateKeepsExactlyEveryThirdScan) {
  const auto before = of_type<LaserMessage>(office());
  const auto after = of_type<LaserMessage>(perturbed("decimate:k=3"));
  ASSERT_EQ(after.size(), (before.size() + 2) / 3);
  for (std::size_t j = 0; j < after.size(); ++j) {
    EXPECT_EQ(after[j].scan.stamp, before[3 * j].scan.stamp);
    EXPECT_EQ(after[j].scan.ranges, before[3 * j].scan.ranges);
  }
  EXPECT_EQ(of_type<OdometryMessage>(perturbed("decimate:k=3")).size(), of_type<OdometryMessage>(office()).size());
}

TEST(FaultInjection, JitterDuplicateAndBackwardsChangeStampsAsStated) {
  const auto before = of_type<LaserMessage>(office());
  const auto jittered = of_type<LaserMessage>(perturbed("jitter:sigma=0.01"));
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < before.size(); ++i) sum_sq += std::pow(jittered[i].scan.stamp - before[i].scan.stamp, 2);
  EXPECT_NEAR(std::sqrt(sum_sq / static_cast<double>(before.size())), 0.01, 0.001);

  const auto doubled = of_type<LaserMessage>(perturbed("duplicate:p=0.2"));
  const double copies = static_cast<double>(doubled.size() - before.size());
  EXPECT_NEAR(copies / static_cast<double>(before.size()), 0.2, 0.03);
  std::size_t repeats = 0;
  for (std::size_t i = 1; i < doubled.size(); ++i) repeats += doubled[i].scan.stamp == doubled[i - 1].scan.stamp ? 1 : 0;
  EXPECT_EQ(static_cast<double>(repeats), copies);

  const auto moved = of_type<LaserMessage>(perturbed("backwards:p=0.1,by=0.5"));
  std::size_t back = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const double shift = before[i].scan.stamp - moved[i].scan.stamp;
    EXPECT_TRUE(shift == 0.0 || std::abs(shift - 0.5) < 1e-9) << i;
    back += shift != 0.0 ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(back) / static_cast<double>(before.size()), 0.1, 0.02);
}

TEST(FaultInjection, SameSeedSameLogOtherSeedOtherLog) {
  test::TempDir dir;
  const std::vector<Fault> faults = {parse_fault("stall:every=20"), parse_fault("jitter"), parse_fault("range-noise"),
                                     parse_fault("spurious-short:p=0.02"), parse_fault("duplicate:p=0.05"),
                                     parse_fault("spurious-far:p=0.02"), parse_fault("mixed-pixels"), parse_fault("glass"),
                                     parse_fault("laser-noise")};
  const auto write = [&](std::uint64_t seed, const std::string& name) {
    Messages messages = office();
    apply_faults(faults, messages, seed);
    write_carmen_log(dir.file(name), {"perturbed"}, messages);
    return file_bytes(dir.file(name));
  };
  const std::string a = write(7, "a.clf"), b = write(7, "b.clf"), c = write(8, "c.clf");
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_GT(a.size(), 1000000u);
  // A deterministic fault does not depend on the seed.
  Messages s1 = perturbed("decimate:k=2", 1), s2 = perturbed("decimate:k=2", 2);
  EXPECT_EQ(laser_odometry(s1), laser_odometry(s2));
}

// ---------------------------------------------------------------------------------------------
// Range faults.

TEST(FaultInjection, RangeNoiseSpuriousMaxAndShortChangeReadingsAsStated) {
  const auto before = of_type<LaserMessage>(office());
  const auto noisy = of_type<LaserMessage>(perturbed("range-noise:sigma=0.05"));
  const auto maxed = of_type<LaserMessage>(perturbed("spurious-max:p=0.1"));
  const auto shorts = of_type<LaserMessage>(perturbed("spurious-short:p=0.1,min=0.05,max=0.5"));
  double sum_sq = 0.0;
  std::size_t valid = 0, became_max = 0, became_short = 0, readings = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const LaserScan& scan = before[i].scan;
    for (std::size_t k = 0; k < scan.size(); ++k) {
      ++readings;
      EXPECT_GE(noisy[i].scan.ranges[k], 0.0);
      if (scan.is_valid(k)) {
        ++valid;
        sum_sq += std::pow(noisy[i].scan.ranges[k] - scan.ranges[k], 2);
        became_max += maxed[i].scan.ranges[k] != scan.ranges[k] ? 1 : 0;
        if (maxed[i].scan.ranges[k] != scan.ranges[k]) {
          EXPECT_EQ(maxed[i].scan.ranges[k], scan.range_max);
        }
      } else {
        EXPECT_EQ(noisy[i].scan.ranges[k], scan.ranges[k]);  // no-returns stay no-returns
        EXPECT_EQ(maxed[i].scan.ranges[k], scan.ranges[k]);
      }
      if (shorts[i].scan.ranges[k] != scan.ranges[k]) {
        ++became_short;
        EXPECT_GE(shorts[i].scan.ranges[k], 0.05);
        EXPECT_LT(shorts[i].scan.ranges[k], 0.5);
      }
    }
  }
  EXPECT_NEAR(std::sqrt(sum_sq / static_cast<double>(valid)), 0.05, 0.001);
  EXPECT_NEAR(static_cast<double>(became_max) / static_cast<double>(valid), 0.1, 0.005);
  EXPECT_NEAR(static_cast<double>(became_short) / static_cast<double>(readings), 0.1, 0.005);
}

// ---------------------------------------------------------------------------------------------
// Geometry faults, read back through CarmenReader.

Messages read_all(const std::string& path) {
  CarmenReader reader(path);
  Messages messages;
  while (auto message = reader.next()) messages.push_back(std::move(*message));
  return messages;
}

// A raw log as a CARMEN logger writes it (no PARAM lines), read back: the reader's conventional
// geometry for n beams. Ranges 0.5 .. 40 m and a few 81.9 m no-returns.
Messages raw_log(const test::TempDir& dir, std::size_t n, const std::string& type = "FLASER") {
  const std::string path = dir.file("raw" + std::to_string(n) + type + ".clf");
  CarmenWriter writer(path);
  for (int s = 0; s < 3; ++s) {
    LaserMessage laser;
    laser.type = type;
    laser.scan.stamp = 10.0 + 0.2 * s;
    for (std::size_t k = 0; k < n; ++k) laser.scan.ranges.push_back(k % 17 == 0 ? 81.9 : 0.5 + 0.25 * static_cast<double>((k * 7 + s) % 160));
    laser.odom_pose = laser.laser_pose = SE2(0.1 * s, 0.0, 0.01 * s);
    writer.write(laser);
  }
  writer.commit();
  return read_all(path);
}

TEST(FaultInjection, GeometryFaultsReadBackWithTheKeptBeamsAngles) {
  test::TempDir dir;
  for (const std::size_t n : {180u, 181u, 360u, 361u}) {
    for (const std::string type : {"FLASER", "RLASER"}) {
      const Messages original = raw_log(dir, n, type);
      const LaserScan& scan = std::get<LaserMessage>(original.front()).scan;
      struct Case {
        std::string spec;
        std::size_t first, step;  // kept beams: first, first + step, ...
      };
      const double resolution_deg = rad_to_deg(scan.angle_increment);
      for (const Case& c : {Case{"beams:k=2", 0, 2}, Case{"beams:k=3", 0, 3},
                            Case{"fov:deg=90", static_cast<std::size_t>(std::lround(45.0 / resolution_deg)), 1},
                            Case{"fov:deg=100.3", static_cast<std::size_t>(std::ceil(39.85 / resolution_deg)), 1}}) {
        SCOPED_TRACE(type + " " + std::to_string(n) + " " + c.spec);
        Messages messages = original;
        apply_faults({parse_fault(c.spec), parse_fault("range-max:max=5.6")}, messages, 1);
        const std::string path = dir.file("out.clf");
        write_carmen_log(path, {}, messages);
        const Messages back = read_all(path);
        ASSERT_EQ(back.size(), original.size());
        for (std::size_t s = 0; s < back.size(); ++s) {
          const LaserScan& in = std::get<LaserMessage>(original[s]).scan;
          const LaserScan& out = std::get<LaserMessage>(back[s]).scan;
          const LaserScan& written = std::get<LaserMessage>(messages[s]).scan;
          EXPECT_EQ(out.ranges, written.ranges);  // exact numbers
          EXPECT_EQ(out.range_max, 5.6);
          EXPECT_EQ(out.T_robot_sensor, in.T_robot_sensor);
          ASSERT_GT(out.size(), 0u);
          for (std::size_t j = 0; j < out.size(); ++j) {
            const std::size_t k = c.first + j * c.step;
            ASSERT_LT(k, in.size());
            EXPECT_NEAR(out.angle(j), in.angle(k), 1e-12) << j;
            EXPECT_EQ(out.ranges[j], in.ranges[k] >= 5.6 ? 5.6 : in.ranges[k]) << j;
            EXPECT_LE(std::abs(out.angle(j)), 0.5 * deg_to_rad(c.step == 1 ? std::stod(c.spec.substr(8)) : 360.0) + 1e-9);
          }
          if (c.step == 1) {  // the kept beams are the ones within +-deg/2, all of them
            const double half = 0.5 * deg_to_rad(std::stod(c.spec.substr(8)));
            std::size_t inside = 0;
            for (std::size_t k = 0; k < in.size(); ++k) inside += std::abs(in.angle(k)) <= half + 1e-9 ? 1 : 0;
            EXPECT_EQ(out.size(), inside);
          } else {
            EXPECT_EQ(out.size(), (in.size() + c.step - 1) / c.step);
          }
        }
      }
    }
  }
}

TEST(FaultInjection, GeometryFaultsRefuseWhatTheyCannotDo) {
  test::TempDir dir;
  Messages messages = raw_log(dir, 180);
  EXPECT_THROW(perturbed("range-max:max=100", 1, messages), Error);  // the log's maximum is 80 m
  EXPECT_THROW(perturbed("fov:deg=0.5", 1, messages), Error);        // no beam within +-0.25 deg left of the axis
}

TEST(CarmenLog, PassThroughKeepsTheGeometryExactly) {
  test::TempDir dir;
  for (const std::size_t n : {180u, 361u}) {
    const Messages original = raw_log(dir, n);
    write_carmen_log(dir.file("copy.clf.gz"), {"a copy"}, original);
    const Messages back = read_all(dir.file("copy.clf.gz"));
    ASSERT_EQ(back.size(), original.size());
    for (std::size_t s = 0; s < back.size(); ++s) {
      const auto& in = std::get<LaserMessage>(original[s]);
      const auto& out = std::get<LaserMessage>(back[s]);
      EXPECT_EQ(out.scan.angle_min, in.scan.angle_min);  // bit for bit
      EXPECT_EQ(out.scan.angle_increment, in.scan.angle_increment);
      EXPECT_EQ(out.field_of_view, in.field_of_view);
      EXPECT_EQ(out.scan.range_max, in.scan.range_max);
      EXPECT_EQ(out.scan.ranges, in.scan.ranges);
      EXPECT_EQ(out.odom_pose, in.odom_pose);
    }
  }
}

TEST(CarmenLog, RefusesAGeometryPARAMLinesCannotDeclare) {
  test::TempDir dir;
  Messages messages = raw_log(dir, 180);
  std::get<LaserMessage>(messages[1]).scan.angle_min += 0.1;
  EXPECT_THROW(write_carmen_log(dir.file("bad.clf"), {}, messages), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.clf")));
}

}  // namespace
}  // namespace slam2d

namespace slam2d {
namespace {

TEST(FaultInjection, RepeatPlaysTheLogAgainAfterItsEnd) {
  const Messages& log = office();
  Messages messages = log;
  const FaultReport report = report_of("repeat:times=3", messages);
  ASSERT_EQ(messages.size(), 3 * log.size());
  EXPECT_EQ(change(report, "copies"), 3.0);
  const double period = change(report, "period_s");
  const double duration = stamp_of(log.back()) - stamp_of(log.front());
  EXPECT_GT(period, duration);
  EXPECT_LT(period, duration + 1.0);
  for (std::size_t copy = 1; copy < 3; ++copy) {
    for (std::size_t i = 0; i < log.size(); i += 97) {
      const SensorMessage& again = messages[copy * log.size() + i];
      EXPECT_NEAR(stamp_of(again), stamp_of(log[i]) + static_cast<double>(copy) * period, 1e-6) << i;
      EXPECT_EQ(again.index(), log[i].index());
      if (const auto* laser = std::get_if<LaserMessage>(&again)) {
        EXPECT_EQ(laser->scan.ranges, std::get<LaserMessage>(log[i]).scan.ranges);
        EXPECT_TRUE(laser->odom_pose.is_approx(std::get<LaserMessage>(log[i]).odom_pose, 0.0));
      }
    }
  }
  // Laser stamps still increase across the seams.
  double previous = -1e300;
  for (const SensorMessage& message : messages) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) {
      EXPECT_GT(laser->scan.stamp, previous);
      previous = laser->scan.stamp;
    }
  }
  Messages once = log;
  report_of("repeat:times=1", once);
  EXPECT_EQ(once.size(), log.size());
  EXPECT_THROW(parse_fault("repeat:times=0"), Error);
  EXPECT_THROW(parse_fault("repeat:times=1001"), Error);
}

TEST(FaultInjection, RepeatBackDrivesTheRouteBackWithoutATeleport) {
  const Messages& log = office();
  Messages messages = log;
  report_of("repeat:times=3,back=1", messages);
  ASSERT_EQ(messages.size(), 3 * log.size());
  EXPECT_EQ(fault_spec(parse_fault("repeat:back=1,times=3")), "repeat:times=3,back=1");
  const std::size_t n = log.size();
  for (std::size_t i = 0; i < n; i += 97) {
    // The second copy is the log backwards, the third forwards again.
    const SensorMessage& back = messages[n + (n - 1 - i)];
    EXPECT_EQ(back.index(), log[i].index());
    EXPECT_NEAR(stamp_of(back) - stamp_of(messages[n]), stamp_of(log.back()) - stamp_of(log[i]), 1e-6) << i;
    if (const auto* laser = std::get_if<LaserMessage>(&back)) {
      EXPECT_EQ(laser->scan.ranges, std::get<LaserMessage>(log[i]).scan.ranges);
      EXPECT_TRUE(laser->odom_pose.is_approx(std::get<LaserMessage>(log[i]).odom_pose, 0.0));
    }
    if (const auto* odometry = std::get_if<OdometryMessage>(&back)) {
      EXPECT_EQ(odometry->reading.tv, -std::get<OdometryMessage>(log[i]).reading.tv);
      EXPECT_EQ(odometry->reading.rv, -std::get<OdometryMessage>(log[i]).reading.rv);
    }
    EXPECT_EQ(messages[2 * n + i].index(), log[i].index());
  }
  // Stamps still increase, and each copy starts where the previous one ended: no pose jump.
  double previous = -1e300;
  std::optional<SE2> last_pose;
  double largest_step = 0.0;
  for (const SensorMessage& message : messages) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) {
      EXPECT_GT(laser->scan.stamp, previous);
      previous = laser->scan.stamp;
      if (last_pose) largest_step = std::max(largest_step, (laser->odom_pose.translation() - last_pose->translation()).norm());
      last_pose = laser->odom_pose;
    }
  }
  EXPECT_LT(largest_step, 0.5);
  EXPECT_THROW(parse_fault("repeat:times=2,back=2"), Error);
}

}  // namespace
}  // namespace slam2d

namespace slam2d {
namespace {

// ---------------------------------------------------------------------------------------------
// Odometry out of step, scan rate, far returns, mixed pixels, glass, a noisy laser.

// A robot whose odometry is linear in time, translation and (unwrapped) heading, so interpolating
// between two samples gives the true pose: it turns through +-pi every 21 s.
SE2 driven_pose(double t) { return SE2(0.5 * (t - 100.0), 0.1 * (t - 100.0), normalize_angle(3.0 + 0.3 * (t - 100.0))); }

// 30 s of it: FLASER at 10 Hz from 100 s, ODOM at 20 Hz from 100.025 s, in stamp order.
Messages driven_log() {
  Messages messages;
  for (int i = 0; i <= 600; ++i) {
    const double t = 100.025 + 0.05 * i;
    if (i % 2 == 0 && i < 600) {
      LaserMessage laser;
      laser.type = "FLASER";
      laser.scan.stamp = 100.0 + 0.05 * i;
      laser.scan.range_max = 80.0;
      laser.scan.angle_increment = deg_to_rad(1.0);
      laser.scan.angle_min = -0.5 * kPi;
      laser.scan.ranges.assign(181, 5.0);
      laser.odom_pose = laser.laser_pose = driven_pose(laser.scan.stamp);
      messages.emplace_back(laser);
    }
    OdometryMessage odom;
    odom.reading.stamp = t;
    odom.reading.pose = driven_pose(t);
    messages.emplace_back(odom);
  }
  return messages;
}

TEST(FaultInjection, OdomShiftPutsThePoseOfStampPlusByBesideEachLine) {
  for (const double by : {0.63, -0.63, 4.9}) {
    SCOPED_TRACE(by);
    Messages messages = driven_log();
    const FaultReport report = report_of("odom-shift:by=" + std::to_string(by), messages);
    const auto lasers = of_type<LaserMessage>(messages);
    const auto odoms = of_type<OdometryMessage>(messages);
    ASSERT_EQ(lasers.size(), 300u);
    // Each chain is held at its own ends.
    const auto clamped = [&](double t, double first, double last) { return std::clamp(t + by, first, last); };
    for (const LaserMessage& laser : lasers) {
      const SE2 expected = driven_pose(clamped(laser.scan.stamp, 100.0, 129.9));
      EXPECT_TRUE(laser.odom_pose.is_approx(expected, 1e-9)) << laser.scan.stamp << " " << laser.odom_pose << " " << expected;
      EXPECT_EQ(laser.laser_pose, laser.odom_pose);  // the repeated triple follows
    }
    for (const OdometryMessage& odom : odoms) {
      const SE2 expected = driven_pose(clamped(odom.reading.stamp, 100.025, 130.025));
      EXPECT_TRUE(odom.reading.pose.is_approx(expected, 1e-9)) << odom.reading.stamp;
    }
    EXPECT_GT(change(report, "odometry_poses_shifted"), 850.0);
    EXPECT_NEAR(change(report, "max_pose_change_m"), std::abs(by) * std::hypot(0.5, 0.1), 1e-9);
  }
}

// A stamp written late (as Intel's are, up to 0.9 s) keeps its pose's place on the path: by = 0
// changes nothing, and the shifted path does not turn back.
TEST(FaultInjection, OdomShiftKeepsTheFileOrderPathWhenAStampIsLate) {
  Messages late = driven_log();
  std::size_t k = 0;
  for (SensorMessage& message : late) {
    if (auto* laser = std::get_if<LaserMessage>(&message); laser != nullptr && k++ == 100) laser->scan.stamp += 0.35;
  }
  Messages unshifted = late;
  EXPECT_EQ(change(report_of("odom-shift:by=0", unshifted), "odometry_poses_shifted"), 0.0);
  EXPECT_EQ(laser_odometry(unshifted), laser_odometry(late));
  const std::vector<SE2> shifted = laser_odometry(perturbed("odom-shift:by=0.63", 1, late));
  const auto lasers = of_type<LaserMessage>(late);
  for (std::size_t i = 1; i < shifted.size(); ++i) {
    EXPECT_GE(shifted[i].x(), shifted[i - 1].x()) << i;  // the robot drives forward throughout
    // Exact wherever the late line is not one of the two samples around stamp + by (the late one,
    // at 110 s, sits at the next line's stamp 110.1 s); itself, the pose at 110.1 + by.
    const double time = i == 100 ? 110.1 + 0.63 : std::min(lasers[i].scan.stamp + 0.63, 129.9);
    if (time <= 109.9 + 1e-9 || time >= 110.1 - 1e-9) {
      EXPECT_TRUE(shifted[i].is_approx(driven_pose(time), 1e-9)) << i;
    }
  }
}

// The largest translation between the laser odometry of `a` and `b` over lines [first, last).
double largest_difference_m(const Messages& a, const Messages& b, std::size_t first, std::size_t last) {
  const std::vector<SE2> pa = laser_odometry(a), pb = laser_odometry(b);
  double largest = 0.0;
  for (std::size_t i = first; i < last; ++i) largest = std::max(largest, (pa[i].translation() - pb[i].translation()).norm());
  return largest;
}

// The fault moves the odometry by the shift the time-offset compensation undoes (both are
// OdometryChain::shifted): on sane stamps, the fault's shift and the compensation's shift back give
// the logged poses (exactly here: the driven path is linear in time). On stamps written in bursts,
// as Intel's logger wrote them, they cannot by construction: in stamp time the path stands still
// between bursts and leaps within them, so every line whose stamp + by falls between two bursts
// gets a pose on the straight line between the bursts' poses, and the poses the burst's lines
// carried (up to a write period of driving) are in no line of the shifted log to come back from.
TEST(FaultInjection, OdomShiftIsUndoneByTheCompensationOnSaneStampsNotOnBursts) {
  constexpr double kBy = 0.63;
  const Messages logged = driven_log();
  Messages round_trip = perturbed("odom-shift:by=0.63", 1, logged);
  shift_scan_odometry(round_trip, -kBy);  // what LogReaderOptions::odometry_time_offset = 0.63 does
  // Lines whose stamp -+ 0.63 stays inside the log's 30 s (the chain's ends are held).
  const std::size_t first = 13, last = 300 - 13;
  EXPECT_LT(largest_difference_m(round_trip, logged, first, last), 1e-9);

  // The same lines written in bursts: every 0.35 s the logger writes the lines taken since, 1 ms
  // apart (43% of Intel's scans are within 50 ms of the one before), and one line 0.5 s late.
  Messages bursty = logged;
  double slot = 0.0;          // s, the current write
  std::size_t in_slot = 0;    // lines written in it so far
  std::size_t lasers = 0;
  for (SensorMessage& message : bursty) {
    auto* laser = std::get_if<LaserMessage>(&message);
    double& stamp = laser != nullptr ? laser->scan.stamp : std::get<OdometryMessage>(message).reading.stamp;
    const double write = 100.0 + 0.35 * std::ceil((stamp - 100.0) / 0.35);
    in_slot = write == slot ? in_slot + 1 : 0;
    slot = write;
    stamp = write + 0.001 * static_cast<double>(in_slot) + (laser != nullptr && lasers++ == 150 ? 0.5 : 0.0);
  }
  Messages bursty_round_trip = perturbed("odom-shift:by=0.63", 1, bursty);
  shift_scan_odometry(bursty_round_trip, -kBy);
  const double error_m = largest_difference_m(bursty_round_trip, bursty, first, last);
  // Not the logged poses (0.12 m off at most here); but within two write periods of driving
  // (0.51 m/s) of them.
  EXPECT_GT(error_m, 0.05);
  EXPECT_LT(error_m, 2 * 0.35 * std::hypot(0.5, 0.1));
}

TEST(FaultInjection, ScanRateKeepsLinesAtLeastAPeriodApartAndDropsNoneItNeedNot) {
  Messages jittered = office();
  apply_faults({parse_fault("jitter:sigma=0.03")}, jittered, 4);  // irregular stamps, some stepping back
  const auto before = of_type<LaserMessage>(jittered);
  Messages messages = jittered;
  const FaultReport report = report_of("scan-rate:hz=3", messages);
  const auto after = of_type<LaserMessage>(messages);
  ASSERT_GT(after.size(), 100u);
  EXPECT_EQ(change(report, "laser_lines_removed"), static_cast<double>(before.size() - after.size()));
  EXPECT_EQ(of_type<OdometryMessage>(messages).size(), of_type<OdometryMessage>(office()).size());
  EXPECT_EQ(after.front().scan.stamp, before.front().scan.stamp);
  std::size_t j = 0;  // after[j] is before[i]
  for (std::size_t i = 0; i < before.size(); ++i) {
    if (j < after.size() && before[i].scan.stamp == after[j].scan.stamp) {
      if (j > 0) {
        EXPECT_GE(after[j].scan.stamp - after[j - 1].scan.stamp, 1.0 / 3.0 - 1e-6) << i;
      }
      ++j;
    } else {  // dropped: within a period of the last kept line
      ASSERT_GT(j, 0u);
      EXPECT_LT(before[i].scan.stamp - after[j - 1].scan.stamp, 1.0 / 3.0 - 1e-6) << i;
    }
  }
  EXPECT_EQ(j, after.size());
  // A rate the log's own 10 Hz meets keeps every line, a stamp 0.1 s after the last included.
  EXPECT_EQ(of_type<LaserMessage>(perturbed("scan-rate:hz=10")).size(), of_type<LaserMessage>(office()).size());
}

TEST(FaultInjection, SpuriousFarMakesFarReturnsBelowTheMaximumRange) {
  const auto before = of_type<LaserMessage>(office());
  const auto after = of_type<LaserMessage>(perturbed("spurious-far:p=0.1"));  // min 20, max 50 clamped to 30
  std::size_t valid = 0, far = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const LaserScan& scan = before[i].scan;
    ASSERT_EQ(scan.range_max, 30.0);
    for (std::size_t k = 0; k < scan.size(); ++k) {
      const double range = after[i].scan.ranges[k];
      if (!scan.is_valid(k)) {
        EXPECT_EQ(range, scan.ranges[k]);
        continue;
      }
      ++valid;
      if (range == scan.ranges[k]) continue;
      ++far;
      EXPECT_GE(range, 20.0);
      EXPECT_LT(range, 30.0);  // a return, not a no-return
    }
  }
  EXPECT_NEAR(static_cast<double>(far) / static_cast<double>(valid), 0.1, 0.005);
  EXPECT_THROW(perturbed("spurious-far:min=30,max=40"), Error);  // nothing below the 30 m scanner's range
}

// One scan: 10 beams at 2 m, a doorway of 10 beams at 6 m, 10 beams at 2 m.
Messages doorway() {
  Messages messages = driven_log();
  messages.resize(1);
  LaserScan& scan = std::get<LaserMessage>(messages.front()).scan;
  scan.ranges.assign(30, 2.0);
  std::fill(scan.ranges.begin() + 10, scan.ranges.begin() + 20, 6.0);
  return messages;
}

TEST(FaultInjection, MixedPixelsFillTheEdgesAsStated) {
  const std::vector<double> logged = std::get<LaserMessage>(doorway().front()).scan.ranges;
  // A single mixed pixel on the far side of each edge: beams 10 and 19, between 2 and 6 m.
  Messages single = doorway();
  const FaultReport report = report_of("mixed-pixels:p=1", single);
  const std::vector<double>& mixed = std::get<LaserMessage>(single.front()).scan.ranges;
  for (std::size_t k = 0; k < mixed.size(); ++k) {
    if (k == 10 || k == 19) {
      EXPECT_GE(mixed[k], 2.0);
      EXPECT_LT(mixed[k], 6.0);
      EXPECT_NE(mixed[k], logged[k]);
    } else {
      EXPECT_EQ(mixed[k], logged[k]) << k;
    }
  }
  EXPECT_EQ(change(report, "edges"), 2.0);
  EXPECT_EQ(change(report, "readings_changed"), 2.0);
  // Alternating stretches of 4 beams from each edge into the doorway: 2, 6, 2, 6 m.
  Messages alternating = doorway();
  apply_faults({parse_fault("mixed-pixels:p=1,alternate=4")}, alternating, 1);
  std::vector<double> expected = logged;
  for (const std::size_t k : {10u, 12u, 19u, 17u}) expected[k] = 2.0;
  EXPECT_EQ(std::get<LaserMessage>(alternating.front()).scan.ranges, expected);
  // An edge smaller than `jump` is no edge; p = 0 changes nothing.
  EXPECT_EQ(std::get<LaserMessage>(perturbed("mixed-pixels:p=1,jump=4", 1, doorway()).front()).scan.ranges, logged);
  EXPECT_EQ(change(report_of("mixed-pixels:p=0", alternating), "readings_changed"), 0.0);
  // On the office, a fraction p of its edges.
  Messages office_log = office();
  const FaultReport some = report_of("mixed-pixels:p=0.3", office_log);
  ASSERT_GT(change(some, "edges"), 1000.0);
  EXPECT_NEAR(change(some, "edges_mixed") / change(some, "edges"), 0.3, 0.03);
}

TEST(FaultInjection, GlassMakesNoReturnsInSectorsFixedInTheWorld) {
  Messages messages = office();
  const FaultReport report = report_of("glass:sectors=3,width=40", messages);
  std::vector<double> centres;
  for (const std::string key : {"sector_1_deg", "sector_2_deg", "sector_3_deg"}) centres.push_back(deg_to_rad(change(report, key)));
  const auto before = of_type<LaserMessage>(office());
  const auto after = of_type<LaserMessage>(messages);
  std::size_t glass = 0, readings = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const LaserScan& scan = before[i].scan;
    for (std::size_t k = 0; k < scan.size(); ++k) {
      const double bearing = before[i].odom_pose.theta() + scan.T_robot_sensor.theta() + scan.angle(k);
      bool inside = false;
      for (const double centre : centres) inside = inside || std::abs(angle_difference(bearing, centre)) <= deg_to_rad(20.0);
      EXPECT_EQ(after[i].scan.ranges[k], inside ? scan.range_max : scan.ranges[k]) << i << " " << k;
      glass += inside ? 1 : 0;
      ++readings;
    }
  }
  EXPECT_GT(glass, readings / 20);
  EXPECT_EQ(laser_odometry(messages), laser_odometry(office()));
  // The seed places the sectors.
  Messages again = office(), other = office();
  EXPECT_EQ(report_of("glass:sectors=3,width=40", again).changes, report.changes);
  EXPECT_NE(report_of("glass:sectors=3,width=40", other, 2).changes, report.changes);
}

TEST(FaultInjection, LaserNoiseTurnsEachScanAndAddsRangeNoise) {
  // Ranges linear in the beam index, so a scan turned by delta reads r_k + slope delta / increment.
  Messages ramp = driven_log();
  for (SensorMessage& message : ramp) {
    if (auto* laser = std::get_if<LaserMessage>(&message)) {
      for (std::size_t k = 0; k < laser->scan.size(); ++k) laser->scan.ranges[k] = 3.0 + 0.01 * static_cast<double>(k);
    }
  }
  const auto before = of_type<LaserMessage>(ramp);
  const auto turned = of_type<LaserMessage>(perturbed("laser-noise:sigma=0,bearing=0.5", 1, ramp));
  double sum_squares = 0.0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const double increment = before[i].scan.angle_increment;
    const double delta = (turned[i].scan.ranges[90] - before[i].scan.ranges[90]) / 0.01 * increment;
    for (std::size_t k = 10; k < 171; ++k) {  // one turn for the whole scan
      EXPECT_NEAR(turned[i].scan.ranges[k] - before[i].scan.ranges[k], 0.01 * delta / increment, 1e-9) << i << " " << k;
    }
    sum_squares += delta * delta;
  }
  EXPECT_NEAR(rad_to_deg(std::sqrt(sum_squares / static_cast<double>(before.size()))), 0.5, 0.075);  // 300 scans
  // Without a turn, range noise as range-noise has it.
  const auto plain = of_type<LaserMessage>(office());
  const auto noisy = of_type<LaserMessage>(perturbed("laser-noise:sigma=0.05,bearing=0"));
  double noise_squares = 0.0;
  std::size_t valid = 0;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    for (std::size_t k = 0; k < plain[i].scan.size(); ++k) {
      if (!plain[i].scan.is_valid(k)) {
        EXPECT_EQ(noisy[i].scan.ranges[k], plain[i].scan.ranges[k]);
        continue;
      }
      noise_squares += std::pow(noisy[i].scan.ranges[k] - plain[i].scan.ranges[k], 2);
      ++valid;
    }
  }
  EXPECT_NEAR(std::sqrt(noise_squares / static_cast<double>(valid)), 0.05, 0.001);
  EXPECT_EQ(change(report_of("laser-noise:sigma=0,bearing=0", ramp), "readings_changed"), 0.0);
}

}  // namespace
}  // namespace slam2d
