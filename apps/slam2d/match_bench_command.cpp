// SPDX-License-Identifier: BSD-3-Clause
// slam2d match-bench LOG --matchers a,b,c: the scan-matching protocol of F. Pomerleau et al.,
// "Comparing ICP variants on real-world data sets", Autonomous Robots 34(3), 2013, on a 2D log:
// pairs of scans a fixed distance apart, their true relative pose from a reference trajectory,
// initial guesses perturbed from it by seeded Gaussian noise; per matcher the success rate, the
// error percentiles and the CPU time per match.

#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>
#include <optional>
#include <variant>

#include "commands.hpp"
#include "json.hpp"
#include "progress.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "slam2d/eval/statistics.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/methods/matcher_registry.hpp"

namespace slam2d::cli {
namespace {

struct MatchBenchOptions {
  std::string log;
  std::string reference;            // trajectory file; empty: the log's own laser poses
  std::vector<std::string> matchers;
  std::size_t pairs = 200;
  double distance = 1.0;            // m between the two scans of a pair (by the reference)
  double perturb_trans = 0.1;       // m, standard deviation per axis of the guess's error
  double perturb_rot_deg = 5.0;     // deg, standard deviation of the guess's heading error
  double success_trans = 0.1;       // m, a match within this and success_rot_deg counts as a success
  double success_rot_deg = 2.0;     // deg
  std::uint64_t seed = 1;
  LogReaderOptions input;             // CARMEN geometry overrides, bag topics and frames
  bool json = false;
  bool quiet = false;
};

struct ReferencedScan {
  PointCloud2 cloud;   // sensor frame, beam order
  SE2 T_world_sensor;  // by the reference
};

struct ScanPairCase {
  std::size_t target = 0;
  std::size_t source = 0;
  SE2 T_target_source;  // the truth
  SE2 guess;
};

std::vector<ReferencedScan> read_scans(const MatchBenchOptions& options) {
  std::optional<Trajectory> reference;
  if (!options.reference.empty()) reference = read_any_trajectory(options.reference);
  const std::optional<StampIndex> index = reference ? std::optional<StampIndex>(StampIndex(*reference)) : std::nullopt;
  LogReader reader(options.log, options.input);
  std::vector<ReferencedScan> scans;
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    SE2 T_world_robot = laser->laser_pose;
    if (index) {
      const std::optional<std::size_t> nearest = index->nearest(laser->scan.stamp, 1e-3);
      if (!nearest) continue;  // the reference has no pose for this scan
      T_world_robot = (*reference)[*nearest].pose;
    } else if (!laser->has_poses) {
      throw ParseError(reader.path(), laser->line, laser->type + " carries no pose; give --reference TRAJ");
    }
    scans.push_back({to_point_cloud(laser->scan, ScanFrame::kSensor).cloud, T_world_robot * laser->scan.T_robot_sensor});
  }
  print_reader_warnings(reader);
  check(scans.size() >= 2, options.log + ": fewer than two front-laser scans with a reference pose");
  return scans;
}

// Pairs: a seeded random first scan, and the first later scan at least `distance` away.
std::vector<ScanPairCase> draw_pairs(const std::vector<ReferencedScan>& scans, const MatchBenchOptions& options) {
  Rng rng(options.seed);
  std::vector<ScanPairCase> pairs;
  const double sigma_rot = deg_to_rad(options.perturb_rot_deg);
  for (std::size_t attempt = 0; pairs.size() < options.pairs && attempt < 20 * options.pairs; ++attempt) {
    const std::size_t i = rng.uniform_index(scans.size());
    std::size_t j = i + 1;
    while (j < scans.size() &&
           (scans[j].T_world_sensor.translation() - scans[i].T_world_sensor.translation()).norm() < options.distance) {
      ++j;
    }
    if (j >= scans.size() || scans[i].cloud.size() < 10 || scans[j].cloud.size() < 10) continue;
    ScanPairCase pair{i, j, scans[i].T_world_sensor.inverse() * scans[j].T_world_sensor, SE2()};
    const SE2 error(rng.gaussian(0.0, options.perturb_trans), rng.gaussian(0.0, options.perturb_trans),
                    rng.gaussian(0.0, sigma_rot));
    pair.guess = pair.T_target_source * error;
    pairs.push_back(pair);
  }
  check(!pairs.empty(), options.log + ": no scan pairs " + fmt::format("{}", options.distance) + " m apart");
  return pairs;
}

double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

struct MatcherScore {
  std::string name;
  double success_rate = 0.0;
  double trans_p[3] = {0.0, 0.0, 0.0};    // m at the 50th, 75th and 95th percentile
  double rot_deg_p[3] = {0.0, 0.0, 0.0};  // deg
  double us_per_match = 0.0;
  double mean_iterations = 0.0;
  std::size_t not_converged = 0;

  JsonObject json() const {
    JsonObject out;
    out.add("success_rate", success_rate);
    out.add("trans_error_p50", trans_p[0]).add("trans_error_p75", trans_p[1]).add("trans_error_p95", trans_p[2]);
    out.add("rot_error_deg_p50", rot_deg_p[0]).add("rot_error_deg_p75", rot_deg_p[1]).add("rot_error_deg_p95", rot_deg_p[2]);
    out.add("us_per_match", us_per_match).add("mean_iterations", mean_iterations).add("not_converged", not_converged);
    return out;
  }
  std::string row() const {
    return fmt::format("{:<18} {:>7.1f}% {:>7.3f} {:>6.3f} {:>6.3f} {:>7.2f} {:>6.2f} {:>6.2f} {:>9.1f}\n", name,
                       100.0 * success_rate, trans_p[0], trans_p[1], trans_p[2], rot_deg_p[0], rot_deg_p[1],
                       rot_deg_p[2], us_per_match);
  }
};

MatcherScore benchmark_matcher(const std::string& name, const std::vector<ReferencedScan>& scans,
                               const std::vector<ScanPairCase>& pairs, const MatchBenchOptions& options) {
  const Matcher matcher = matcher_from_argument(name);
  std::vector<double> trans_errors;
  std::vector<double> rot_errors;
  std::size_t successes = 0;
  MatcherScore score;
  score.name = name;
  double cpu = 0.0;
  Progress progress("match-bench " + name, options.quiet);
  for (const ScanPairCase& pair : pairs) {
    const double start = thread_cpu_seconds();
    const MatchResult result = matcher(scans[pair.target].cloud, scans[pair.source].cloud, pair.guess);
    cpu += thread_cpu_seconds() - start;
    const SE2 error = pair.T_target_source.inverse() * result.T_target_source;
    trans_errors.push_back(error.translation().norm());
    rot_errors.push_back(rad_to_deg(std::abs(normalize_angle(error.theta()))));
    if (trans_errors.back() <= options.success_trans && rot_errors.back() <= options.success_rot_deg) ++successes;
    if (!result.converged) ++score.not_converged;
    score.mean_iterations += result.iterations;
    progress.update(static_cast<double>(trans_errors.size()) / static_cast<double>(pairs.size()),
                    fmt::format("{} pairs", trans_errors.size()));
  }
  progress.finish();
  const auto n = static_cast<double>(pairs.size());
  score.success_rate = static_cast<double>(successes) / n;
  const double levels[3] = {50.0, 75.0, 95.0};
  for (int k = 0; k < 3; ++k) {
    score.trans_p[k] = percentile(trans_errors, levels[k]);
    score.rot_deg_p[k] = percentile(rot_errors, levels[k]);
  }
  score.us_per_match = 1e6 * cpu / n;
  score.mean_iterations /= n;
  return score;
}

void run_match_bench(const MatchBenchOptions& options) {
  check(!options.matchers.empty(), "match-bench: --matchers is empty");
  check(options.pairs >= 1, "match-bench: --pairs must be >= 1");
  check(options.distance >= 0.0 && std::isfinite(options.distance), "match-bench: --distance must be >= 0");
  check(options.perturb_trans >= 0.0 && options.perturb_rot_deg >= 0.0, "match-bench: perturbations must be >= 0");
  for (const std::string& name : options.matchers) (void)matcher_from_argument(name);  // fail before reading the log
  const std::vector<ReferencedScan> scans = read_scans(options);
  const std::vector<ScanPairCase> pairs = draw_pairs(scans, options);
  JsonObject results;
  std::string table = fmt::format("{} pairs {} m apart, guess error sigma {} m / {} deg, success within {} m / {} deg\n",
                                  pairs.size(), options.distance, options.perturb_trans, options.perturb_rot_deg,
                                  options.success_trans, options.success_rot_deg);
  table += fmt::format("{:<18} {:>8} {:>21} {:>21} {:>9}\n", "matcher", "success", "trans m p50/p75/p95",
                       "rot deg p50/p75/p95", "us/match");
  for (const std::string& name : options.matchers) {
    const MatcherScore score = benchmark_matcher(name, scans, pairs, options);
    results.add(name, score.json());
    table += score.row();
  }
  if (!options.json) {
    std::fputs(table.c_str(), stdout);
    return;
  }
  JsonObject summary;
  summary.add("log", options.log).add("reference", options.reference.empty() ? "log laser poses" : options.reference);
  summary.add("scans", scans.size()).add("pairs", pairs.size()).add("distance", options.distance);
  summary.add("perturb_trans", options.perturb_trans).add("perturb_rot_deg", options.perturb_rot_deg);
  summary.add("success_trans", options.success_trans).add("success_rot_deg", options.success_rot_deg);
  summary.add("seed", static_cast<std::size_t>(options.seed)).add("matchers", results);
  std::fputs(summary.dump().c_str(), stdout);
}

}  // namespace

void add_match_bench_command(CLI::App& app) {
  auto options = std::make_shared<MatchBenchOptions>();
  CLI::App* command = app.add_subcommand(
      "match-bench", "Scan-matcher benchmark on a log (Pomerleau et al. 2013 protocol): success rate, error percentiles, time");
  command->add_option("log", options->log, "CARMEN log (plain or .gz); its laser poses are the reference by default")
      ->required();
  command->add_option("--reference", options->reference, "Reference trajectory (slam2d text format), matched by stamp");
  command->add_option("--matchers", options->matchers, "Matcher names or preset .yaml files, comma separated")
      ->delimiter(',')
      ->required();
  command->add_option("--pairs", options->pairs, "Number of scan pairs")->capture_default_str();
  command->add_option("--distance", options->distance, "m between the scans of a pair")->capture_default_str();
  command->add_option("--perturb-trans", options->perturb_trans, "m, std. dev. per axis of the initial guess error")
      ->capture_default_str();
  command->add_option("--perturb-rot", options->perturb_rot_deg, "deg, std. dev. of the initial heading error")
      ->capture_default_str();
  command->add_option("--success-trans", options->success_trans, "m, success threshold")->capture_default_str();
  command->add_option("--success-rot", options->success_rot_deg, "deg, success threshold")->capture_default_str();
  command->add_option("--seed", options->seed, "Seed of the pair choice and perturbations")->capture_default_str();
  add_sensor_options(command, options->input);
  command->add_flag("--json", options->json, "Print the results as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_match_bench(*options); });
}

}  // namespace slam2d::cli
