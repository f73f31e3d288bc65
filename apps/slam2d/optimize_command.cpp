// SPDX-License-Identifier: BSD-3-Clause
// slam2d optimize GRAPH --out OUT: sparse pose adjustment (Konolige et al. 2010,
// src/slam2d/optim/sparse_pose_adjustment.hpp) of a g2o or TORO pose graph from its own initial
// guess or from an estimate of the edges alone (optim/initial_guess.hpp), whichever scores the
// lower chi2 (--initial), plain or with a robust kernel on the loop edges (--robust); the output
// format follows OUT's extension (.g2o or .graph, optionally .gz).

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "commands.hpp"
#include "json.hpp"
#include "run_stats.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/optim/sparse_pose_adjustment.hpp"

namespace slam2d::cli {
namespace {

struct OptimizeOptions {
  std::string graph;
  std::string out;
  int max_iterations = SparsePoseAdjustmentConfig{}.max_iterations;
  InitialGuessChoice initial = InitialGuessChoice::kBetter;
  RobustKernel robust{.type = RobustKernelType::kNone, .scale = 1.0};
  bool json = false;
  bool quiet = false;
};

const char* format_name(PoseGraphFormat format) { return format == PoseGraphFormat::kToro ? "toro" : "g2o"; }

void run_optimize(const OptimizeOptions& options) {
  pose_graph_format_of(options.out);  // a bad extension fails before the work
  SparsePoseAdjustmentConfig config;
  config.max_iterations = options.max_iterations;
  config.loop_kernel = options.robust;
  validate(config);
  const PoseGraphFile file = read_pose_graph(options.graph);
  PoseGraph graph = to_pose_graph(file);
  for (PoseGraphEdge& edge : graph.edges) edge.robust = std::abs(edge.to - edge.from) > 1;  // loop edges

  const RunClock clock;
  const StartedOptimization started = optimize_pose_graph(graph, config, options.initial);
  const SparsePoseAdjustmentResult& result = started.result;
  const double cpu = clock.cpu_seconds();
  const double wall = clock.wall_seconds();

  const std::filesystem::path out(options.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  write_pose_graph(options.out, to_pose_graph_file(graph, file));

  JsonObject summary;
  summary.add("input", options.graph).add("format", format_name(file.format));
  summary.add("nodes", graph.size()).add("edges", graph.edges.size());
  summary.add("initial_guess", std::string(choice_name(started.start))).add("given_chi2", started.given_chi2);
  if (!std::isnan(started.estimate_chi2)) summary.add("estimated_start_chi2", started.estimate_chi2);
  summary.add("initial_chi2", result.initial_chi2).add("final_chi2", result.final_chi2);
  summary.add("robust", std::string(choice_name(options.robust.type)));
  summary.add("iterations", result.iterations).add("converged", result.converged);
  summary.add("cpu_s", cpu).add("wall_s", wall).add("output", options.out);
  std::fputs(options.json ? summary.dump().c_str() : summary.text().c_str(), stdout);
}

}  // namespace

void add_optimize_command(CLI::App& app) {
  auto options = std::make_shared<OptimizeOptions>();
  CLI::App* command = app.add_subcommand("optimize", "Sparse pose adjustment of a g2o or TORO pose graph (Konolige 2010)");
  command->add_option("graph", options->graph, "Pose graph: g2o (VERTEX_SE2/EDGE_SE2) or TORO (VERTEX2/EDGE2), plain or .gz")
      ->required();
  command->add_option("--out", options->out, "Optimised graph: .g2o writes g2o, .graph writes TORO (+ .gz: compressed)")
      ->required();
  command->add_option("--max-iterations", options->max_iterations, "Levenberg-Marquardt iterations (accepted and rejected steps)")
      ->capture_default_str();
  command->add_option("--initial", options->initial,
                      "Where to start: the file's poses (given), the odometry chain's spanning tree (tree), headings then "
                      "positions by linear least squares (orientations), the one of the file's and the orientations' "
                      "poses with the lower chi2 (better), or each of these two, keeping the lower final chi2 (both)")
      ->transform(CLI::CheckedTransformer(choice_map<InitialGuessChoice>()))
      ->default_str("better");
  command->add_option("--robust", options->robust.type,
                      "Kernel on the loop edges (between nodes that are not consecutive): none, huber, cauchy, tukey or dcs")
      ->transform(CLI::CheckedTransformer(choice_map<RobustKernelType>()))
      ->default_str("none");
  command->add_option("--robust-scale", options->robust.scale, "The kernel's scale k in sqrt(chi2) units (dcs: Phi = k^2)")
      ->capture_default_str();
  command->add_flag("--json", options->json, "Print the summary as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line (the optimisation prints none)");
  command->callback([options] { run_optimize(*options); });
}

}  // namespace slam2d::cli
