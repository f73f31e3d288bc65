// SPDX-License-Identifier: BSD-3-Clause
// slam2d perturb LOG --out LOG2 --fault KIND[:key=value,...] ... --seed N: a log (CARMEN or bag)
// with injected faults (sim/fault_injection.hpp, docs/faults.md), written atomically in the format
// LOG2's name asks for (io/log_writer.hpp).

#include <fmt/core.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "commands.hpp"
#include "json.hpp"
#include "progress.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/log_writer.hpp"
#include "slam2d/sim/fault_injection.hpp"

namespace slam2d::cli {

namespace {

struct PerturbOptions {
  std::string log;
  std::string out;
  std::vector<std::string> faults;  // specs, applied in order
  std::uint64_t seed = 1;
  bool json = false;
  bool quiet = false;
};

struct MessageCounts {
  std::size_t laser = 0;
  std::size_t odometry = 0;
  std::size_t true_pose = 0;
};

MessageCounts count_messages(const std::vector<SensorMessage>& messages) {
  MessageCounts counts;
  for (const SensorMessage& message : messages) {
    if (std::holds_alternative<LaserMessage>(message)) ++counts.laser;
    if (std::holds_alternative<OdometryMessage>(message)) ++counts.odometry;
    if (std::holds_alternative<TruePoseMessage>(message)) ++counts.true_pose;
  }
  return counts;
}

std::vector<SensorMessage> read_log(const std::string& path, Progress& progress) {
  LogReaderOptions as_logged;
  as_logged.carmen.repair_reverse_odometry = false;  // faults are injected into the log as it is
  LogReader reader(path, as_logged);
  return read_all(reader, [&](double fraction, std::size_t n) { progress.update(fraction, fmt::format("{} messages read", n)); });
}

JsonObject counts_json(const MessageCounts& counts) {
  JsonObject json;
  json.add("laser", counts.laser).add("odom", counts.odometry).add("truepos", counts.true_pose);
  return json;
}

void run_perturb(const PerturbOptions& options) {
  std::vector<Fault> faults;
  for (const std::string& spec : options.faults) faults.push_back(parse_fault(spec));  // bad specs stop here
  Progress progress("perturb", options.quiet);
  std::vector<SensorMessage> messages = read_log(options.log, progress);
  const MessageCounts before = count_messages(messages);
  progress.update(-1.0, "injecting faults");
  const std::vector<FaultReport> reports = apply_faults(faults, messages, options.seed);

  const std::string name = std::filesystem::path(options.log).filename().string();
  std::vector<std::string> comments = {"slam2d perturb of " + name + ", seed " + std::to_string(options.seed)};
  for (const FaultReport& report : reports) comments.push_back("fault " + report.spec);
  const std::filesystem::path out(options.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  progress.update(-1.0, "writing");
  write_log(options.out, log_format_for_output(options.out), messages, comments);
  progress.finish();

  JsonObject summary;
  summary.add("log", options.log).add("out", options.out).add("seed", static_cast<std::size_t>(options.seed));
  summary.add("messages_in", counts_json(before)).add("messages_out", counts_json(count_messages(messages)));
  JsonObject faults_json;
  for (std::size_t i = 0; i < reports.size(); ++i) {
    JsonObject fault;
    fault.add("spec", reports[i].spec);
    for (const auto& [key, value] : reports[i].changes) fault.add(key, value);
    faults_json.add(std::to_string(i + 1), fault);
  }
  summary.add("faults", faults_json);
  if (options.json) {
    std::fputs(summary.dump().c_str(), stdout);
  } else if (!options.quiet) {
    std::fputs(summary.text().c_str(), stdout);
  }
}

}  // namespace

void add_perturb_command(CLI::App& app) {
  auto options = std::make_shared<PerturbOptions>();
  std::string kinds;
  for (const std::string& kind : fault_kinds()) kinds += (kinds.empty() ? "" : ", ") + kind;
  CLI::App* command = app.add_subcommand("perturb", "Write a log with injected faults (docs/faults.md)");
  command->add_option("log", options->log, "Log: CARMEN (plain or .gz), ROS 1 bag, MCAP file or rosbag2 folder")->required();
  command->add_option("--out", options->out,
                      "Perturbed log to write; its name gives the format: .bag, .mcap, a rosbag2 folder (no extension), "
                      "else CARMEN (.gz: gzip)")
      ->required();
  command->add_option("--fault", options->faults, "KIND[:key=value,...], repeatable, applied in order; kinds: " + kinds)
      ->required()
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->add_option("--seed", options->seed, "Seed of the random faults")->capture_default_str();
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "No progress line; no summary unless --json");
  command->callback([options] { run_perturb(*options); });
}

}  // namespace slam2d::cli
