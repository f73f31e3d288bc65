// SPDX-License-Identifier: BSD-3-Clause
// slam2d match-bench LOG --reference REF --matchers a,b,c: the scan-matching protocol of
// F. Pomerleau, F. Colas, R. Siegwart, S. Magnenat, "Comparing ICP variants on real-world data
// sets", Autonomous Robots 34(3), 2013, on a 2D log. Pairs of scans a fixed distance apart take
// their relative pose from an explicit reference (a trajectory, a SLAM-corrected log's poses, or
// the raw odometry, labelled as such); the initial guess is that pose perturbed at several levels
// of difficulty, with the same pairs and the same unit draws at every level and for every matcher;
// each case's translation and rotation error is kept, so that the full distributions (CDFs) can be
// drawn (bench/datasets/match_bench_cdf.py), and summarised per level and matcher by the success
// rate, the 50th, 75th and 95th percentiles and the maximum, and the CPU time per match.

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iterator>
#include <optional>
#include <sstream>
#include <variant>

#include "commands.hpp"
#include "json.hpp"
#include "progress.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/eval/statistics.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/methods/matcher_registry.hpp"

namespace slam2d::cli {
namespace {

constexpr double kStampTolerance = 1e-3;  // s, a reference pose belongs to a scan within this

struct MatchBenchOptions {
  std::string log;
  std::string reference;            // TRAJ | corrected | corrected:LOG | odometry (required)
  std::vector<std::string> matchers;
  std::string levels = "0.05:2,0.1:5,0.2:10,0.5:20";  // m:deg, standard deviations of the guess error
  std::size_t pairs = 200;
  double distance = 1.0;            // m between the two scans of a pair (by the reference)
  double success_trans = 0.1;       // m, a match within this and success_rot_deg counts as a success
  double success_rot_deg = 2.0;     // deg
  double min_coverage = 0.5;        // 1, share of the log's scans the reference must give a pose for
  std::uint64_t seed = 1;
  std::string out;                  // folder for cases.csv and summary.json; empty: none
  LogReaderOptions input;           // CARMEN geometry overrides, bag topics and frames
  bool json = false;
  bool quiet = false;
};

// ---------------------------------------------------------------------------------------------
// Perturbation levels: "M:DEG,M:DEG,..." (standard deviations of the guess's error).

struct PerturbationLevel {
  double sigma_trans = 0.0;    // m, per axis
  double sigma_rot_deg = 0.0;  // deg

  std::string name() const { return fmt::format("{}m_{}deg", sigma_trans, sigma_rot_deg); }
};

std::vector<PerturbationLevel> parse_levels(const std::string& text) {
  const std::string usage = "match-bench: --levels '" + text +
                            "': expected M:DEG[,M:DEG...], standard deviations in m and deg, each >= 0 and finite";
  std::vector<PerturbationLevel> levels;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    const std::size_t colon = item.find(':');
    check(colon != std::string::npos, usage);
    PerturbationLevel level;
    try {
      std::size_t used_trans = 0, used_rot = 0;
      const std::string trans = item.substr(0, colon), rot = item.substr(colon + 1);
      level.sigma_trans = std::stod(trans, &used_trans);
      level.sigma_rot_deg = std::stod(rot, &used_rot);
      check(used_trans == trans.size() && used_rot == rot.size(), usage);
    } catch (const std::logic_error&) {  // std::invalid_argument, std::out_of_range
      throw Error(usage);
    }
    check(std::isfinite(level.sigma_trans) && std::isfinite(level.sigma_rot_deg) && level.sigma_trans >= 0.0 &&
              level.sigma_rot_deg >= 0.0,
          usage);
    for (const PerturbationLevel& other : levels) {
      check(other.name() != level.name(), "match-bench: --levels repeats " + item);
    }
    levels.push_back(level);
  }
  check(!levels.empty() && text.back() != ',', usage);
  return levels;
}

// ---------------------------------------------------------------------------------------------
// The reference: where each scan's true pose comes from, said in every output.

enum class ReferenceKind { kTrajectory, kCorrectedLog, kOdometry };

struct ReferenceSpec {
  ReferenceKind kind = ReferenceKind::kTrajectory;
  std::string source;  // the trajectory file or the corrected log; the log itself for odometry

  const char* kind_name() const {
    switch (kind) {
      case ReferenceKind::kTrajectory: return "trajectory";
      case ReferenceKind::kCorrectedLog: return "corrected-log";
      case ReferenceKind::kOdometry: return "odometry";
    }
    return "";
  }
  std::string description() const {
    switch (kind) {
      case ReferenceKind::kTrajectory: return "trajectory " + source + " (robot poses matched by stamp)";
      case ReferenceKind::kCorrectedLog: return "SLAM-corrected laser poses of " + source;
      case ReferenceKind::kOdometry:
        return "RAW ODOMETRY of " + source + ", not ground truth: the errors include the odometry's own drift";
    }
    return "";
  }
};

ReferenceSpec parse_reference(const std::string& argument, const std::string& log) {
  if (argument == "odometry") return {ReferenceKind::kOdometry, log};
  if (argument == "corrected") return {ReferenceKind::kCorrectedLog, log};
  if (argument.rfind("corrected:", 0) == 0) {
    const std::string path = argument.substr(10);
    check(!path.empty(), "match-bench: --reference corrected:FILE names no file");
    return {ReferenceKind::kCorrectedLog, path};
  }
  check(!argument.empty(), "match-bench: --reference is empty");
  return {ReferenceKind::kTrajectory, argument};
}

// A front-laser scan of the log, with its reference pose once known.
struct BenchScan {
  double stamp = 0.0;
  PointCloud2 cloud;        // sensor frame, beam order
  SE2 T_robot_sensor;
  SE2 T_world_robot_odom;   // the odometry pose logged with the scan
  SE2 T_world_robot_laser;  // the pose the log gives the scan (a corrected log: the corrected pose)
  bool has_poses = true;
  std::size_t line = 0;
  std::optional<SE2> T_world_sensor;  // by the reference
};

struct LogScans {
  std::vector<BenchScan> scans;
  Trajectory odometry_readings;  // the ODOM messages, for the raw-log check
};

LogScans read_log_scans(const std::string& path, const LogReaderOptions& input) {
  LogReader reader(path, input);
  LogScans out;
  while (auto message = reader.next()) {
    if (const auto* odometry = std::get_if<OdometryMessage>(&*message)) {
      out.odometry_readings.push_back(odometry->reading.stamp, odometry->reading.pose);
      continue;
    }
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    BenchScan scan{laser->scan.stamp, to_point_cloud(laser->scan, ScanFrame::kSensor).cloud, laser->scan.T_robot_sensor,
                   laser->odom_pose, laser->laser_pose, laser->has_poses, laser->line, std::nullopt};
    // ROBOTLASER1 logs the laser's pose; FLASER the robot's.
    if (laser->type == "ROBOTLASER1") scan.T_world_robot_laser = laser->laser_pose * laser->scan.T_robot_sensor.inverse();
    out.scans.push_back(std::move(scan));
  }
  print_reader_warnings(reader);
  check(out.scans.size() >= 2, path + ": fewer than two front-laser scans");
  return out;
}

// A raw CARMEN log repeats its odometry as the scans' poses: refuse it as a "corrected" log when
// nearly every scan pose lies within 5 cm of one of the two odometry readings around its stamp
// (raw Intel, ACES, FR079: 98-100 %; their corrected logs: 55-85 %).
void check_not_raw_odometry(const std::string& path, const LogScans& log) {
  if (log.odometry_readings.size() < 10) return;
  const Trajectory odometry = log.odometry_readings.sorted_by_stamp();
  const std::vector<StampedPose>& readings = odometry.poses();
  std::size_t near = 0;
  for (const BenchScan& scan : log.scans) {
    const auto after = std::lower_bound(readings.begin(), readings.end(), scan.stamp,
                                        [](const StampedPose& reading, double stamp) { return reading.stamp < stamp; });
    const auto close = [&](auto it) {
      return (it->pose.translation() - scan.T_world_robot_laser.translation()).norm() < 0.05;
    };
    if ((after != readings.end() && close(after)) || (after != readings.begin() && close(std::prev(after)))) ++near;
  }
  const std::size_t compared = log.scans.size();
  if (static_cast<double>(near) < 0.95 * static_cast<double>(compared)) return;
  throw Error(fmt::format("{}: its scan poses are its odometry ({} of {} within 5 cm of an ODOM reading next to the "
                          "scan in time): a raw log, not a SLAM-corrected one; give --reference odometry to use raw "
                          "odometry knowingly, or a reference trajectory",
                          path, near, compared));
}

// T_world_robot of each scan of `log` by the reference; returns how many scans have one.
std::size_t attach_reference(LogScans& log, const ReferenceSpec& reference, const MatchBenchOptions& options) {
  std::optional<Trajectory> trajectory;
  if (reference.kind == ReferenceKind::kTrajectory) {
    trajectory = read_any_trajectory(reference.source);
  } else if (reference.kind == ReferenceKind::kCorrectedLog) {
    const bool same_log = reference.source == options.log;
    const LogScans other = same_log ? LogScans{} : read_log_scans(reference.source, options.input);
    const LogScans& corrected = same_log ? log : other;
    check_not_raw_odometry(reference.source, corrected);
    if (!same_log) {
      trajectory.emplace();
      for (const BenchScan& scan : corrected.scans) trajectory->push_back(scan.stamp, scan.T_world_robot_laser);
    }
  }
  const std::optional<StampIndex> index = trajectory ? std::optional<StampIndex>(StampIndex(*trajectory)) : std::nullopt;
  std::size_t covered = 0;
  for (BenchScan& scan : log.scans) {
    std::optional<SE2> T_world_robot;
    if (index) {
      const std::optional<std::size_t> nearest = index->nearest(scan.stamp, kStampTolerance);
      if (nearest) T_world_robot = (*trajectory)[*nearest].pose;
    } else if (!scan.has_poses) {
      throw ParseError(options.log, scan.line, "a scan without a logged pose; give --reference TRAJ");
    } else {
      T_world_robot = reference.kind == ReferenceKind::kOdometry ? scan.T_world_robot_odom : scan.T_world_robot_laser;
    }
    if (T_world_robot) {
      scan.T_world_sensor = *T_world_robot * scan.T_robot_sensor;
      ++covered;
    }
  }
  const double share = static_cast<double>(covered) / static_cast<double>(log.scans.size());
  if (share < options.min_coverage || covered < 2) {
    throw Error(fmt::format("{}: the reference covers {} of the {} scans of {} (a pose within {} s of the scan's "
                            "stamp), under --min-coverage {}: not a reference for this log",
                            reference.source, covered, log.scans.size(), options.log, kStampTolerance,
                            options.min_coverage));
  }
  if (covered < log.scans.size()) {
    std::fputs(fmt::format("{}: warning: the reference covers {} of the {} scans of {}; pairs are drawn among those\n",
                           reference.source, covered, log.scans.size(), options.log)
                   .c_str(),
               stderr);
  }
  return covered;
}

// ---------------------------------------------------------------------------------------------
// Pairs and their perturbations.

struct ScanPairCase {
  std::size_t target = 0;  // index into the log's scans
  std::size_t source = 0;
  SE2 T_target_source;     // by the reference
  Eigen::Vector3d unit_draw = Eigen::Vector3d::Zero();  // N(0, 1) per axis, scaled by each level's sigmas
};

// Pairs: a seeded random first scan with a reference pose, and the first later one at least
// `distance` away. The guess error at a level is (sigma_t z_x, sigma_t z_y, sigma_r z_theta) for the
// pair's one draw z: an isotropic Gaussian translation (uniform direction) and a Gaussian heading,
// the same draw at every level (common random numbers), so levels differ only by their scale.
std::vector<ScanPairCase> draw_pairs(const std::vector<BenchScan>& scans, const MatchBenchOptions& options) {
  std::vector<std::size_t> referenced;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (scans[i].T_world_sensor && scans[i].cloud.size() >= 10) referenced.push_back(i);
  }
  check(referenced.size() >= 2, options.log + ": fewer than two scans with a reference pose and 10 points");
  Rng rng(options.seed);
  std::vector<ScanPairCase> pairs;
  for (std::size_t attempt = 0; pairs.size() < options.pairs && attempt < 20 * options.pairs; ++attempt) {
    const std::size_t k = rng.uniform_index(referenced.size());
    const SE2& T_world_target = *scans[referenced[k]].T_world_sensor;
    std::size_t m = k + 1;
    while (m < referenced.size() &&
           (scans[referenced[m]].T_world_sensor->translation() - T_world_target.translation()).norm() < options.distance) {
      ++m;
    }
    if (m >= referenced.size()) continue;
    ScanPairCase pair{referenced[k], referenced[m], T_world_target.inverse() * *scans[referenced[m]].T_world_sensor,
                      Eigen::Vector3d::Zero()};
    pair.unit_draw = Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian());
    pairs.push_back(pair);
  }
  check(!pairs.empty(), options.log + ": no scan pairs " + fmt::format("{}", options.distance) + " m apart");
  return pairs;
}

SE2 perturbed_guess(const ScanPairCase& pair, const PerturbationLevel& level) {
  const SE2 error(level.sigma_trans * pair.unit_draw.x(), level.sigma_trans * pair.unit_draw.y(),
                  deg_to_rad(level.sigma_rot_deg) * pair.unit_draw.z());
  return pair.T_target_source * error;
}

// ---------------------------------------------------------------------------------------------
// Running the matchers.

double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// One match: the pair at one level by one matcher.
struct MatchCase {
  std::size_t pair = 0;
  SE2 guess;
  SE2 estimate;
  double trans_error = 0.0;    // m, |t| of T_true^-1 T_estimate
  double rot_error_deg = 0.0;  // deg, |theta| of the same
  int iterations = 0;
  bool converged = false;
  double cpu_us = 0.0;
  bool success = false;
};

struct CaseSummary {
  double success_rate = 0.0;
  double trans[4] = {0.0, 0.0, 0.0, 0.0};  // m: p50, p75, p95, max
  double rot_deg[4] = {0.0, 0.0, 0.0, 0.0};
  double us_per_match = 0.0;
  double mean_iterations = 0.0;
  std::size_t not_converged = 0;

  JsonObject json() const {
    JsonObject out;
    out.add("success_rate", success_rate);
    out.add("trans_error_p50", trans[0]).add("trans_error_p75", trans[1]).add("trans_error_p95", trans[2]);
    out.add("trans_error_max", trans[3]);
    out.add("rot_error_deg_p50", rot_deg[0]).add("rot_error_deg_p75", rot_deg[1]).add("rot_error_deg_p95", rot_deg[2]);
    out.add("rot_error_deg_max", rot_deg[3]);
    out.add("us_per_match", us_per_match).add("mean_iterations", mean_iterations).add("not_converged", not_converged);
    return out;
  }
  std::string row(const std::string& name) const {
    return fmt::format("{:<18} {:>7.1f}% {:>7.3f} {:>6.3f} {:>6.3f} {:>7.3f} {:>6.2f} {:>6.2f} {:>6.2f} {:>7.2f} {:>9.1f}\n",
                       name, 100.0 * success_rate, trans[0], trans[1], trans[2], trans[3], rot_deg[0], rot_deg[1],
                       rot_deg[2], rot_deg[3], us_per_match);
  }
};

CaseSummary summarize(const std::vector<MatchCase>& cases) {
  CaseSummary summary;
  std::vector<double> trans, rot;
  for (const MatchCase& c : cases) {
    trans.push_back(c.trans_error);
    rot.push_back(c.rot_error_deg);
    summary.success_rate += c.success ? 1.0 : 0.0;
    summary.us_per_match += c.cpu_us;
    summary.mean_iterations += c.iterations;
    if (!c.converged) ++summary.not_converged;
  }
  const auto n = static_cast<double>(cases.size());
  summary.success_rate /= n;
  summary.us_per_match /= n;
  summary.mean_iterations /= n;
  const double ranks[4] = {50.0, 75.0, 95.0, 100.0};
  for (int k = 0; k < 4; ++k) {
    summary.trans[k] = percentile(trans, ranks[k]);
    summary.rot_deg[k] = percentile(rot, ranks[k]);
  }
  return summary;
}

std::vector<MatchCase> run_matcher(const std::string& name, const PerturbationLevel& level,
                                   const std::vector<BenchScan>& scans, const std::vector<ScanPairCase>& pairs,
                                   const MatchBenchOptions& options) {
  const Matcher matcher = matcher_from_argument(name);
  std::vector<MatchCase> cases;
  cases.reserve(pairs.size());
  Progress progress("match-bench " + name + " " + level.name(), options.quiet);
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const ScanPairCase& pair = pairs[p];
    MatchCase c;
    c.pair = p;
    c.guess = perturbed_guess(pair, level);
    const double start = thread_cpu_seconds();
    const MatchResult result = matcher(scans[pair.target].cloud, scans[pair.source].cloud, c.guess);
    c.cpu_us = 1e6 * (thread_cpu_seconds() - start);
    c.estimate = result.T_target_source;
    const SE2 error = pair.T_target_source.inverse() * result.T_target_source;
    c.trans_error = error.translation().norm();
    c.rot_error_deg = rad_to_deg(std::abs(normalize_angle(error.theta())));
    c.iterations = result.iterations;
    c.converged = result.converged;
    c.success = c.trans_error <= options.success_trans && c.rot_error_deg <= options.success_rot_deg;
    cases.push_back(c);
    progress.update(static_cast<double>(p + 1) / static_cast<double>(pairs.size()), fmt::format("{} pairs", p + 1));
  }
  progress.finish();
  return cases;
}

// ---------------------------------------------------------------------------------------------
// Outputs.

constexpr const char* kCsvHeader =
    "matcher,level,sigma_trans,sigma_rot_deg,pair,target,source,target_stamp,source_stamp,"
    "true_x,true_y,true_theta,guess_x,guess_y,guess_theta,estimate_x,estimate_y,estimate_theta,"
    "trans_error,rot_error_deg,iterations,converged,cpu_us,success\n";

std::string csv_rows(const std::string& matcher, const PerturbationLevel& level, const std::vector<BenchScan>& scans,
                     const std::vector<ScanPairCase>& pairs, const std::vector<MatchCase>& cases) {
  std::string rows;
  for (const MatchCase& c : cases) {
    const ScanPairCase& pair = pairs[c.pair];
    const SE2& t = pair.T_target_source;
    rows += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.1f},{}\n", matcher,
                        level.name(), level.sigma_trans, level.sigma_rot_deg, c.pair, pair.target, pair.source,
                        scans[pair.target].stamp, scans[pair.source].stamp, t.x(), t.y(), t.theta(), c.guess.x(),
                        c.guess.y(), c.guess.theta(), c.estimate.x(), c.estimate.y(), c.estimate.theta(),
                        c.trans_error, c.rot_error_deg, c.iterations, c.converged ? 1 : 0, c.cpu_us, c.success ? 1 : 0);
  }
  return rows;
}

void run_match_bench(const MatchBenchOptions& options) {
  check(!options.matchers.empty(), "match-bench: --matchers is empty");
  check(options.pairs >= 1, "match-bench: --pairs must be >= 1");
  check(options.distance >= 0.0 && std::isfinite(options.distance), "match-bench: --distance must be >= 0");
  check(options.success_trans > 0.0 && options.success_rot_deg > 0.0, "match-bench: success thresholds must be > 0");
  check(options.min_coverage >= 0.0 && options.min_coverage <= 1.0, "match-bench: --min-coverage must be in [0, 1]");
  const std::vector<PerturbationLevel> levels = parse_levels(options.levels);
  const ReferenceSpec reference = parse_reference(options.reference, options.log);
  for (const std::string& name : options.matchers) (void)matcher_from_argument(name);  // fail before reading the log

  LogScans log = read_log_scans(options.log, options.input);
  const std::size_t covered = attach_reference(log, reference, options);
  const std::vector<ScanPairCase> pairs = draw_pairs(log.scans, options);

  std::string table = fmt::format("reference: {}\n", reference.description());
  table += fmt::format("{} pairs of scans >= {} m apart among {} of {} scans; success within {} m and {} deg; seed {}\n",
                       pairs.size(), options.distance, covered, log.scans.size(), options.success_trans,
                       options.success_rot_deg, options.seed);
  std::string csv = kCsvHeader;
  JsonObject levels_json;
  for (const PerturbationLevel& level : levels) {
    table += fmt::format("\nlevel {}: guess error sigma {} m per axis, {} deg\n", level.name(), level.sigma_trans,
                         level.sigma_rot_deg);
    table += fmt::format("{:<18} {:>8} {:>28} {:>27} {:>9}\n", "matcher", "success", "trans m p50/p75/p95/max",
                         "rot deg p50/p75/p95/max", "us/match");
    JsonObject matchers_json;
    for (const std::string& name : options.matchers) {
      const std::vector<MatchCase> cases = run_matcher(name, level, log.scans, pairs, options);
      const CaseSummary summary = summarize(cases);
      matchers_json.add(name, summary.json());
      table += summary.row(name);
      csv += csv_rows(name, level, log.scans, pairs, cases);
    }
    JsonObject level_json;
    level_json.add("sigma_trans", level.sigma_trans).add("sigma_rot_deg", level.sigma_rot_deg);
    level_json.add("matchers", matchers_json);
    levels_json.add(level.name(), level_json);
  }

  JsonObject reference_json;
  reference_json.add("kind", reference.kind_name()).add("source", reference.source);
  reference_json.add("description", reference.description());
  reference_json.add("ground_truth", reference.kind != ReferenceKind::kOdometry);
  JsonObject summary;
  summary.add("log", options.log).add("reference", reference_json);
  summary.add("scans", log.scans.size()).add("scans_with_reference", covered);
  summary.add("pairs", pairs.size()).add("distance", options.distance);
  summary.add("perturbation", "guess = T_true * (sigma_t z_x, sigma_t z_y, sigma_r z_theta), z ~ N(0, I) once per pair, "
                              "the same z at every level and for every matcher");
  summary.add("success_trans", options.success_trans).add("success_rot_deg", options.success_rot_deg);
  summary.add("seed", static_cast<std::size_t>(options.seed)).add("matchers", options.matchers);
  summary.add("levels", levels_json);
  if (!options.out.empty()) {
    std::filesystem::create_directories(options.out);
    write_file_atomically((std::filesystem::path(options.out) / "cases.csv").string(), csv);
    write_file_atomically((std::filesystem::path(options.out) / "summary.json").string(), summary.dump());
  }
  std::fputs(options.json ? summary.dump().c_str() : table.c_str(), stdout);
}

}  // namespace

void add_match_bench_command(CLI::App& app) {
  auto options = std::make_shared<MatchBenchOptions>();
  CLI::App* command = app.add_subcommand(
      "match-bench",
      "Scan-matcher benchmark on a log against an explicit reference (Pomerleau et al. 2013 protocol): success rate, "
      "error distributions per perturbation level, time");
  command->add_option("log", options->log, "Log whose scans are matched (CARMEN, plain or .gz, or a bag)")->required();
  command
      ->add_option("--reference", options->reference,
                   "Where the scans' true poses come from: TRAJ (a trajectory file, slam2d text or TUM, robot poses "
                   "matched by stamp within 1 ms), 'corrected' (the log's own scan poses, when LOG is a SLAM-corrected "
                   "log), 'corrected:LOG2' (a corrected log's scan poses, matched by stamp) or 'odometry' (the raw "
                   "odometry, labelled as not ground truth)")
      ->required();
  command->add_option("--matchers", options->matchers, "Matcher names or preset .yaml files, comma separated")
      ->delimiter(',')
      ->required();
  command->add_option("--levels", options->levels, "Perturbation levels M:DEG,...: std. dev. of the guess error, m per axis and deg")
      ->capture_default_str();
  command->add_option("--pairs", options->pairs, "Number of scan pairs (the same at every level)")->capture_default_str();
  command->add_option("--distance", options->distance, "m between the scans of a pair")->capture_default_str();
  command->add_option("--success-trans", options->success_trans, "m, success threshold")->capture_default_str();
  command->add_option("--success-rot", options->success_rot_deg, "deg, success threshold")->capture_default_str();
  command->add_option("--min-coverage", options->min_coverage, "Share of the log's scans the reference must cover")
      ->capture_default_str();
  command->add_option("--seed", options->seed, "Seed of the pair choice and perturbations")->capture_default_str();
  command->add_option("--out", options->out, "Folder for cases.csv (one row per match) and summary.json");
  add_sensor_options(command, options->input);
  command->add_flag("--json", options->json, "Print the results as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_match_bench(*options); });
}

}  // namespace slam2d::cli
