// SPDX-License-Identifier: BSD-3-Clause
// slam2d eval TRAJ (--relations FILE | --reference TRAJ): accuracy of a trajectory, and with
// --errors-csv / --errors-json each error it is made of, for plots (slam2d report, evo-style tools):
//   --relations: one row per relation evaluated: stamp_from, stamp_to, x_from, y_from, x_to, y_to
//     (the estimate's positions at the two stamps, in its own frame), translation_m, rotation_deg;
//   --reference: one row per associated pose: stamp, x, y (the estimate aligned onto the
//     reference, as the ATE aligns it), ate_m; the JSON also holds the RPE windows: stamp_from,
//     stamp_to, translation_m, rotation_deg.
// The JSON holds each table column by column: {"relations": {"stamp_from": [...], ...}}.

#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "eval_summary.hpp"
#include "json.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/io/trajectory_io.hpp"

namespace slam2d::cli {

namespace {

struct EvalOptions {
  std::string trajectory;
  std::string relations;
  std::optional<double> max_span;  // s: only relations whose stamps are at most this far apart
  std::optional<double> min_span;  // s: ... more than this far apart
  std::string reference;
  double stamp_tolerance = 0.001;
  double rpe_delta = 1.0;
  std::string rpe_window = "distance";  // distance (m) | time (s)
  std::string errors_csv;   // each error, one row each; empty: none
  std::string errors_json;  // each error, column by column; empty: none
  bool json = false;
};

/// A table of numbers, column by column (the header is there even with no row).
struct ErrorTable {
  ErrorTable() = default;
  explicit ErrorTable(const std::vector<std::string>& names) {
    for (const std::string& name : names) columns.emplace_back(name, std::vector<double>());
  }
  std::vector<std::pair<std::string, std::vector<double>>> columns;
  std::vector<double>& column(const std::string& name) {
    for (auto& [key, values] : columns) {
      if (key == name) return values;
    }
    return columns.emplace_back(name, std::vector<double>()).second;
  }
  std::string csv() const {
    std::string text;
    for (std::size_t c = 0; c < columns.size(); ++c) text += (c == 0 ? "" : ",") + columns[c].first;
    text += "\n";
    const std::size_t rows = columns.empty() ? 0 : columns.front().second.size();
    for (std::size_t r = 0; r < rows; ++r) {
      for (std::size_t c = 0; c < columns.size(); ++c) text += (c == 0 ? "" : ",") + json_number(columns[c].second[r]);
      text += "\n";
    }
    return text;
  }
  JsonObject json() const {
    JsonObject object;
    for (const auto& [key, values] : columns) object.add(key, values);
    return object;
  }
};

ErrorTable relation_table(const RelationErrorResult& result, const std::vector<Relation>& relations) {
  ErrorTable table({"stamp_from", "stamp_to", "x_from", "y_from", "x_to", "y_to", "translation_m", "rotation_deg"});
  for (const RelationError& e : result.errors) {
    table.column("stamp_from").push_back(relations[e.relation_index].stamp_from);
    table.column("stamp_to").push_back(relations[e.relation_index].stamp_to);
    table.column("x_from").push_back(e.T_world_from.x());
    table.column("y_from").push_back(e.T_world_from.y());
    table.column("x_to").push_back(e.T_world_to.x());
    table.column("y_to").push_back(e.T_world_to.y());
    table.column("translation_m").push_back(e.translation);
    table.column("rotation_deg").push_back(rad_to_deg(e.rotation));
  }
  return table;
}

ErrorTable pose_table(const AteResult& ate, const Trajectory& estimate) {
  ErrorTable table({"stamp", "x", "y", "ate_m"});
  for (std::size_t i = 0; i < ate.errors.size(); ++i) {
    const StampedPose& pose = estimate[ate.estimate_indices[i]];
    const Eigen::Vector2d p = ate.T_reference_estimate * pose.pose.translation();
    table.column("stamp").push_back(pose.stamp);
    table.column("x").push_back(p.x());
    table.column("y").push_back(p.y());
    table.column("ate_m").push_back(ate.errors[i]);
  }
  return table;
}

ErrorTable window_table(const RpeResult& rpe) {
  ErrorTable table({"stamp_from", "stamp_to", "translation_m", "rotation_deg"});
  for (const RpeWindowError& e : rpe.errors) {
    table.column("stamp_from").push_back(e.stamp_from);
    table.column("stamp_to").push_back(e.stamp_to);
    table.column("translation_m").push_back(e.translation);
    table.column("rotation_deg").push_back(e.rotation_deg);
  }
  return table;
}

void run_eval(const EvalOptions& options) {
  check(!options.relations.empty() || !options.reference.empty(), "eval: give --relations FILE or --reference TRAJ");
  check(options.stamp_tolerance >= 0.0, "eval: --stamp-tolerance must not be negative");
  const Trajectory estimate = read_any_trajectory(options.trajectory);
  JsonObject json;
  json.add("trajectory", options.trajectory).add("poses", estimate.size());
  ErrorTable table;  // the CSV's
  JsonObject errors;
  if (!options.relations.empty()) {
    json.add("relations_file", options.relations);
    std::vector<Relation> relations = read_relations(options.relations);
    if (options.max_span || options.min_span) {  // the relations whose stamps lie within the span
      std::erase_if(relations, [&](const Relation& r) {
        const double span = std::abs(r.stamp_to - r.stamp_from);
        return (options.max_span && span > *options.max_span) || (options.min_span && span <= *options.min_span);
      });
      check(!relations.empty(), "eval: no relation of " + options.relations + " lies within the span given");
      if (options.max_span) json.add("max_span_s", *options.max_span);
      if (options.min_span) json.add("min_span_s", *options.min_span);
    }
    table = relation_table(add_relation_error(json, estimate, relations, options.stamp_tolerance), relations);
    errors.add("relations", table.json());
  } else {
    json.add("reference", options.reference);
    const RpeConfig rpe{.window = options.rpe_window == "time" ? RpeWindow::kTime : RpeWindow::kDistance,
                        .delta = options.rpe_delta,
                        .stamp_tolerance = options.stamp_tolerance};
    const ReferenceError result = add_reference_error(json, estimate, read_any_trajectory(options.reference), rpe);
    table = pose_table(result.ate, estimate);
    errors.add("poses", table.json()).add("rpe_windows", window_table(result.rpe).json());
  }
  if (!options.errors_csv.empty()) write_file_atomically(options.errors_csv, table.csv());
  if (!options.errors_json.empty()) write_file_atomically(options.errors_json, errors.dump());
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
  command->add_option("--max-span", options->max_span, "s: score only the relations whose two stamps are at most this far apart")
      ->check(CLI::PositiveNumber)->needs(relations);
  command->add_option("--min-span", options->min_span, "s: score only the relations whose two stamps are more than this far apart")
      ->check(CLI::NonNegativeNumber)->needs(relations);
  reference->excludes(relations);
  command->add_option("--stamp-tolerance", options->stamp_tolerance, "s: poses are matched by nearest stamp within this")
      ->capture_default_str();
  command->add_option("--rpe-delta", options->rpe_delta, "RPE window: m of travelled distance, or s with --rpe-window time")
      ->capture_default_str();
  command->add_option("--rpe-window", options->rpe_window,
                      "How the RPE window is measured: distance (KITTI) or time (Sturm et al. 2012)")
      ->check(CLI::IsMember({"distance", "time"}))
      ->capture_default_str();
  command->add_option("--errors-csv", options->errors_csv,
                      "Write each error to FILE: per relation, or per pose (ATE) with --reference");
  command->add_option("--errors-json", options->errors_json,
                      "Write each error to FILE as JSON columns (with --reference also the RPE windows)");
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->callback([options] { run_eval(*options); });
}

}  // namespace slam2d::cli
