// SPDX-License-Identifier: BSD-3-Clause
// slam2d simulate --out LOG: a CARMEN log (and its ground truth) from the built-in simulated world.

#include <cstdio>

#include "commands.hpp"
#include "json.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/sim/simulator.hpp"

namespace slam2d::cli {

namespace {

struct SimulateOptions {
  std::string out;
  std::string truth;
  SimulationConfig config;
  bool json = false;
  bool quiet = false;
};

void run_simulate(const SimulateOptions& options) {
  const SimulatedRun run = simulate(options.config);
  write_carmen_log(options.out, run_comments(run.config), run.messages);
  if (!options.truth.empty()) write_trajectory(options.truth, run.truth);
  JsonObject json;
  json.add("log", options.out).add("truth", options.truth).add("world", options.config.world);
  json.add("seed", static_cast<std::size_t>(options.config.seed)).add("duration_s", options.config.duration);
  json.add("scans", run.truth.size()).add("messages", run.messages.size());
  json.add("path_length_m", run.truth.path_length());
  if (options.json) {
    std::fputs(json.dump().c_str(), stdout);
  } else if (!options.quiet) {
    std::fputs(json.text().c_str(), stdout);
  }
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* command = app.add_subcommand("simulate", "Write a simulated CARMEN log and its ground-truth trajectory");
  command->add_option("--out", options->out, "CARMEN log to write (.gz for gzip)")->required();
  command->add_option("--truth", options->truth, "Ground-truth trajectory to write ('timestamp x y theta')");
  command->add_option("--seed", options->config.seed, "Seed of every random stream")->capture_default_str();
  command->add_option("--world", options->config.world, "Simulated world")->capture_default_str();
  command->add_option("--duration", options->config.duration, "s of simulated time")->capture_default_str();
  command->add_option("--beams", options->config.laser.beams, "Laser beams per scan")->capture_default_str();
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "Print nothing on success");
  command->callback([options] { run_simulate(*options); });
}

}  // namespace slam2d::cli
