// SPDX-License-Identifier: BSD-3-Clause
// slam2d demo: simulate the office world, map it with the flagship (--method, graph SLAM by
// default) and, for contrast, with the odometry alone, and score both trajectories against the
// truth. Each run's outputs go to its own folder, OUT/<method>/; the report of both (slam2d report
// with the truth and the log) to OUT/report/index.html.

#include <fmt/core.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.hpp"
#include "eval_summary.hpp"
#include "json.hpp"
#include "map_job.hpp"
#include "report_data.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/sim/simulator.hpp"

namespace slam2d::cli {

namespace {

struct DemoOptions {
  std::string out = "out/demo";
  std::string method = "graph";
  SimulationConfig config;
  bool json = false;
  bool quiet = false;
};

void run_demo(const DemoOptions& options) {
  const std::filesystem::path dir(options.out);
  std::filesystem::create_directories(dir);
  const std::string log = (dir / "office.clf").string();
  const std::string truth_path = (dir / "truth.txt").string();
  const SimulatedRun run = simulate(options.config);
  write_carmen_log(log, run_comments(run.config), run.messages);
  write_trajectory(truth_path, run.truth);

  std::vector<std::string> methods = {options.method};
  if (options.method != "odometry") methods.push_back("odometry");  // the contrast: what the robot knew alone
  JsonObject runs;
  std::string lines;
  ReportInputs report;
  report.reference = truth_path;
  report.log = log;
  for (const std::string& method : methods) {
    MapJobOptions map_options;
    map_options.log = log;
    map_options.out_dir = (dir / method).string();
    map_options.method = method;
    map_options.quiet = options.quiet;
    const MapJobResult mapped = run_map_job(map_options);
    report.run_dirs.push_back(map_options.out_dir);
    JsonObject accuracy;
    const ReferenceError error = add_reference_error(accuracy, mapped.trajectory, run.truth, RpeConfig{});
    runs.add(method, JsonObject().add("out", map_options.out_dir).add("map", mapped.summary).add("error_vs_truth", accuracy));
    lines += fmt::format("  {:<13}ATE rmse {:.3f} m (max {:.3f} m), RPE over 1 m {:.3f} m, {:.2f} deg (rmse); "
                         "map {}/map.png ({} x {} cells at {} m)\n",
                         method + ":", error.ate.rmse, error.ate.max, error.rpe.translation.rmse,
                         error.rpe.rotation_deg.rmse, map_options.out_dir, mapped.map.width, mapped.map.height,
                         mapped.map.resolution);
  }
  const WrittenReport page = write_report(collect_report(report), (dir / "report").string());
  JsonObject json;
  json.add("report", page.path);
  json.add("world", options.config.world).add("seed", static_cast<std::size_t>(options.config.seed));
  json.add("log", log).add("truth", truth_path).add("out", options.out);
  json.add("runs", runs);
  write_file_atomically((dir / "demo.json").string(), json.dump());
  if (options.json) {
    std::fputs(json.dump().c_str(), stdout);
    return;
  }
  std::fputs(fmt::format("slam2d demo: {:.0f} s in the simulated '{}' world, {} scans, {:.0f} m driven\n"
                         "  log and truth: {}, {}\n"
                         "  error against the truth, and the map (trajectory.txt, summary.json beside it):\n{}"
                         "  the report (maps, errors, loop closures, scan replay): open {} in a browser\n",
                         options.config.duration, options.config.world, run.truth.size(), run.truth.path_length(),
                         log, truth_path, lines, std::filesystem::absolute(page.path).string())
                 .c_str(),
             stdout);
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* command = app.add_subcommand(
      "demo", "Simulate the office world, map it with graph SLAM and with the odometry alone, print the errors against the truth and write the HTML report");
  command->add_option("--out", options->out, "Output folder")->capture_default_str();
  command->add_option("--method", options->method, "The mapping method to show (the odometry alone runs beside it)")
      ->check(CLI::IsMember(map_methods()))
      ->capture_default_str();
  command->add_option("--seed", options->config.seed, "Simulation seed")->capture_default_str();
  command->add_option("--duration", options->config.duration, "s of simulated time")->capture_default_str();
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_demo(*options); });
}

}  // namespace slam2d::cli
