// SPDX-License-Identifier: BSD-3-Clause
// slam2d report RUN_DIR... [--relations FILE | --reference TRAJ] [--log LOG] --out REPORT_DIR:
// one self-contained HTML page (REPORT_DIR/index.html) comparing the runs: maps, trajectories
// coloured by their error, error plots and tables, loop closures, a scan replay (docs/report.md).
// The data and the page come from report_data.cpp.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "commands.hpp"
#include "json.hpp"
#include "report_data.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/error.hpp"

namespace slam2d::cli {

namespace {

struct ReportOptions {
  ReportInputs inputs;
  std::string out;
  bool json = false;
  bool quiet = false;
};

void run_report(const ReportOptions& options) {
  if (!options.quiet && !options.json) std::fprintf(stderr, "report: reading %zu runs\n", options.inputs.run_dirs.size());
  const ReportData data = collect_report(options.inputs);
  const WrittenReport written = write_report(data, options.out);
  std::vector<std::string> names;
  for (const ReportRun& run : data.runs) names.push_back(run.name);
  JsonObject summary;
  summary.add("path", written.path).add("bytes", written.bytes).add("runs", names).add("replay_scans", data.replay.size());
  if (options.json) std::fputs(summary.dump().c_str(), stdout);
  else if (!options.quiet) std::fputs(summary.text().c_str(), stdout);
}

}  // namespace

void add_report_command(CLI::App& app) {
  auto options = std::make_shared<ReportOptions>();
  CLI::App* command = app.add_subcommand("report", "One self-contained HTML page comparing `slam2d map` runs");
  command->add_option("run_dirs", options->inputs.run_dirs, "Output folders of `slam2d map --out`")->required();
  auto* relations = command->add_option("--relations", options->inputs.relations,
                                        "Relations file: each run's relation error (Kuemmerle 2009)");
  auto* reference = command->add_option("--reference", options->inputs.reference,
                                        "Reference trajectory: each run's ATE per pose");
  relations->excludes(reference);
  reference->excludes(relations);
  command->add_option("--stamp-tolerance", options->inputs.stamp_tolerance,
                      "s: poses are matched by nearest stamp within this")
      ->capture_default_str();
  command->add_option("--log", options->inputs.log, "The log the runs came from: a scan replay on the base run's map (the most accurate run)");
  add_sensor_options(command, options->inputs.log_options);
  command->add_option("--out", options->out, "Folder for index.html")->required();
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "No progress or summary lines");
  command->callback([options] { run_report(*options); });
}

}  // namespace slam2d::cli
