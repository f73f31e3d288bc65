// SPDX-License-Identifier: BSD-3-Clause
// slam2d eval TRAJ (--relations FILE | --reference TRAJ): accuracy of a trajectory.

#include <fmt/core.h>

#include <cstdio>
#include <string>

#include "commands.hpp"
#include "eval_summary.hpp"
#include "json.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/io/trajectory_io.hpp"

namespace slam2d::cli {

namespace {

struct EvalOptions {
  std::string trajectory;
  std::string relations;
  std::string reference;
  double stamp_tolerance = 0.001;
  double rpe_delta = 1.0;
  std::string rpe_window = "distance";  // distance (m) | time (s)
  bool json = false;
};

void run_eval(const EvalOptions& options) {
  check(!options.relations.empty() || !options.reference.empty(), "eval: give --relations FILE or --reference TRAJ");
  check(options.stamp_tolerance >= 0.0, "eval: --stamp-tolerance must not be negative");
  const Trajectory estimate = read_any_trajectory(options.trajectory);
  JsonObject json;
  json.add("trajectory", options.trajectory).add("poses", estimate.size());
  if (!options.relations.empty()) {
    json.add("relations_file", options.relations);
    add_relation_error(json, estimate, read_relations(options.relations), options.stamp_tolerance);
  } else {
    json.add("reference", options.reference);
    const RpeConfig rpe{.window = options.rpe_window == "time" ? RpeWindow::kTime : RpeWindow::kDistance,
                        .delta = options.rpe_delta,
                        .stamp_tolerance = options.stamp_tolerance};
    add_reference_error(json, estimate, read_any_trajectory(options.reference), rpe);
  }
  std::fputs(options.json ? json.dump().c_str() : json.text().c_str(), stdout);
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto options = std::make_shared<EvalOptions>();
  CLI::App* command = app.add_subcommand("eval", "Error of a trajectory against relations (Kuemmerle 2009) or a reference trajectory");
  command->add_option("trajectory", options->trajectory, "Trajectory file: 'timestamp x y theta' per line")->required();
  auto* relations = command->add_option("--relations", options->relations, "Relations file 't1 t2 x y z roll pitch yaw'");
  auto* reference = command->add_option("--reference", options->reference, "Reference trajectory: ATE and RPE");
  relations->excludes(reference);
  reference->excludes(relations);
  command->add_option("--stamp-tolerance", options->stamp_tolerance, "s: poses are matched by nearest stamp within this")
      ->capture_default_str();
  command->add_option("--rpe-delta", options->rpe_delta, "RPE window: m of travelled distance, or s with --rpe-window time")
      ->capture_default_str();
  command->add_option("--rpe-window", options->rpe_window,
                      "How the RPE window is measured: distance (KITTI) or time (Sturm et al. 2012)")
      ->check(CLI::IsMember({"distance", "time"}))
      ->capture_default_str();
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->callback([options] { run_eval(*options); });
}

}  // namespace slam2d::cli
