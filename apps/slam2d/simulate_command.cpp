// SPDX-License-Identifier: BSD-3-Clause
// slam2d simulate --out LOG: a CARMEN log (and its ground truth) from the built-in simulated world.

#include <cstdio>
#include <optional>

#include "commands.hpp"
#include "json.hpp"
#include "slam2d/io/carmen_log.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/sim/simulator.hpp"

namespace slam2d::cli {

namespace {

struct SimulateOptions {
  std::string out;
  std::string truth;
  std::string config_file;  // YAML: any SimulationConfig field; the flags below override it
  std::optional<std::uint64_t> seed;
  std::optional<std::string> world;
  std::optional<double> duration;
  std::optional<int> beams;
  bool json = false;
  bool quiet = false;
};

SimulationConfig simulation_config(const SimulateOptions& options) {
  SimulationConfig config;
  if (!options.config_file.empty()) read_valid_config(ConfigNode::load(options.config_file), config);
  if (options.seed) config.seed = *options.seed;
  if (options.world) config.world = *options.world;
  if (options.duration) config.duration = *options.duration;
  if (options.beams) config.laser.beams = *options.beams;
  validate(config);
  return config;
}

void run_simulate(SimulateOptions& options) {
  const SimulationConfig config = simulation_config(options);  // the file's, then the flags'
  const SimulatedRun run = simulate(config);
  write_carmen_log(options.out, run_comments(run.config), run.messages);
  if (!options.truth.empty()) write_trajectory(options.truth, run.truth);
  JsonObject json;
  json.add("log", options.out).add("truth", options.truth).add("world", config.world);
  json.add("seed", static_cast<std::size_t>(config.seed)).add("duration_s", config.duration);
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
  const SimulationConfig defaults;
  command->add_option("--config", options->config_file,
                      "YAML of SimulationConfig's fields (sim/simulator.hpp), e.g. 'laser: {rate_hz: 1.7}'; the flags below override it");
  command->add_option("--seed", options->seed, "Seed of every random stream")->default_str(std::to_string(defaults.seed));
  command->add_option("--world", options->world, "Simulated world: office or hospital")->default_str(defaults.world);
  command->add_option("--duration", options->duration, "s of simulated time")->default_str(std::to_string(static_cast<int>(defaults.duration)));
  command->add_option("--beams", options->beams, "Laser beams per scan")->default_str(std::to_string(defaults.laser.beams));
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "Print nothing on success");
  command->callback([options] { run_simulate(*options); });
}

}  // namespace slam2d::cli
