// SPDX-License-Identifier: BSD-3-Clause
// slam2d demo: simulate the office world, map it (--method, odometry by default), and score the
// trajectory against the truth.

#include <fmt/core.h>

#include <cstdio>
#include <filesystem>

#include "commands.hpp"
#include "eval_summary.hpp"
#include "json.hpp"
#include "map_job.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/sim/simulator.hpp"

namespace slam2d::cli {

namespace {

struct DemoOptions {
  std::string out = "out/demo";
  std::string method = "odometry";
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

  MapJobOptions map_options;
  map_options.log = log;
  map_options.out_dir = options.out;
  map_options.method = options.method;
  map_options.quiet = options.quiet;
  const MapJobResult mapped = run_map_job(map_options);
  JsonObject accuracy;
  const ReferenceError error = add_reference_error(accuracy, mapped.trajectory, run.truth, RpeConfig{});
  JsonObject json;
  json.add("world", options.config.world).add("seed", static_cast<std::size_t>(options.config.seed));
  json.add("log", log).add("truth", truth_path).add("out", options.out);
  json.add("map", mapped.summary).add("error_vs_truth", accuracy);
  write_file_atomically((dir / "demo.json").string(), json.dump());
  if (options.json) {
    std::fputs(json.dump().c_str(), stdout);
    return;
  }
  std::fputs(fmt::format("slam2d demo: {:.0f} s in the simulated '{}' world, {} scans, {:.0f} m driven\n"
                         "  log and truth:   {}, {}\n"
                         "  map ({}):  {}/map.pgm, map.yaml, map.png ({} x {} cells at {} m)\n"
                         "  trajectory:      {}/trajectory.txt\n"
                         "  error vs truth:  ATE rmse {:.3f} m (max {:.3f} m), RPE over 1 m: {:.3f} m, {:.2f} deg (rmse)\n",
                         options.config.duration, options.config.world, run.truth.size(), run.truth.path_length(),
                         log, truth_path, options.method, options.out, mapped.map.width, mapped.map.height, mapped.map.resolution,
                         options.out, error.ate.rmse, error.ate.max, error.rpe.translation.rmse,
                         error.rpe.rotation_deg.rmse)
                 .c_str(),
             stdout);
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* command = app.add_subcommand("demo", "Simulate the office world, map it, and print the error against the truth");
  command->add_option("--out", options->out, "Output folder")->capture_default_str();
  command->add_option("--method", options->method, "Mapping method")
      ->check(CLI::IsMember(map_methods()))
      ->capture_default_str();
  command->add_option("--seed", options->config.seed, "Simulation seed")->capture_default_str();
  command->add_option("--duration", options->config.duration, "s of simulated time")->capture_default_str();
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_demo(*options); });
}

}  // namespace slam2d::cli
