// SPDX-License-Identifier: BSD-3-Clause
// slam2d spoil GRAPH --out OUT --share S --placement P --seed N: the pose graph with false loop
// closures added (optim/false_loop_closures.hpp), for judging robust back ends; the false edges
// follow the graph's own, from the index the summary gives. OUT's extension picks the format.

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "json.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/optim/false_loop_closures.hpp"
#include "slam2d/optim/pose_graph.hpp"

namespace slam2d::cli {
namespace {

struct SpoilOptions {
  std::string graph;
  std::string out;
  FalseClosureConfig config;
  bool json = false;
};

void run_spoil(const SpoilOptions& options) {
  pose_graph_format_of(options.out);  // a bad extension fails before the work
  validate(options.config);
  const PoseGraphFile file = read_pose_graph(options.graph);
  const SpoiledGraph spoiled = add_false_loop_closures(to_pose_graph(file), options.config);
  write_pose_graph(options.out, to_pose_graph_file(spoiled.graph, file));

  JsonObject summary;
  summary.add("input", options.graph).add("nodes", spoiled.graph.size());
  summary.add("edges", spoiled.graph.edges.size()).add("loop_edges", spoiled.loop_edges);
  summary.add("false_edges", spoiled.false_edges).add("first_false_edge", spoiled.first_false);
  summary.add("placement", std::string(choice_name(options.config.placement)));
  summary.add("seed", options.config.seed).add("output", options.out);
  std::fputs(options.json ? summary.dump().c_str() : summary.text().c_str(), stdout);
}

}  // namespace

void add_spoil_command(CLI::App& app) {
  auto options = std::make_shared<SpoilOptions>();
  CLI::App* command = app.add_subcommand("spoil", "Add false loop closures to a pose graph (Vertigo's protocol), seeded");
  command->add_option("graph", options->graph, "Pose graph: g2o or TORO, plain or .gz")->required();
  command->add_option("--out", options->out, "Spoiled graph: .g2o writes g2o, .graph writes TORO (+ .gz: compressed)")
      ->required();
  command->add_option("--share", options->config.share, "False edges among the loop edges afterwards, in [0, 0.95]")
      ->capture_default_str();
  command->add_option("--placement", options->config.placement,
                      "random, local (within --local-span nodes), random-grouped or local-grouped (runs of --group-size)")
      ->transform(CLI::CheckedTransformer(choice_map<FalseClosurePlacement>()))
      ->default_str("random");
  command->add_option("--group-size", options->config.group_size, "Edges per group (grouped placements)")->capture_default_str();
  command->add_option("--local-span", options->config.local_span, "Nodes: how far a local closure reaches along the chain")
      ->capture_default_str();
  command->add_option("--max-translation", options->config.max_translation, "m: a false measurement's x and y within +-this")
      ->capture_default_str();
  command->add_option("--seed", options->config.seed, "Of every random draw")->capture_default_str();
  command->add_flag("--json", options->json, "Print the summary as JSON");
  command->callback([options] { run_spoil(*options); });
}

}  // namespace slam2d::cli
