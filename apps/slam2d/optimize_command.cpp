// SPDX-License-Identifier: BSD-3-Clause
// slam2d optimize GRAPH --out OUT: sparse pose adjustment (Konolige et al. 2010,
// src/slam2d/optim/sparse_pose_adjustment.hpp) of a g2o or TORO pose graph from its own initial
// guess or from an estimate of the edges alone (optim/initial_guess.hpp), whichever scores the
// lower chi2 (--initial), behind the loop edges' consistency gate (--gate pairs, the default:
// src/slam2d/optim/loop_consistency.hpp), plain or with a robust kernel on the loop edges (--robust;
// tls by graduated non-convexity), reporting the loop edges kept (and, where the false ones are
// known, precision and recall); the output format follows OUT's extension (.g2o or .graph, optionally .gz).

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "json.hpp"
#include "run_stats.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/optim/loop_consistency.hpp"
#include "slam2d/optim/pose_graph.hpp"
#include "slam2d/optim/sparse_pose_adjustment.hpp"

namespace slam2d::cli {
namespace {

struct OptimizeOptions {
  std::string graph;
  std::string out;
  int max_iterations = SparsePoseAdjustmentConfig{}.max_iterations;
  InitialGuessChoice initial = InitialGuessChoice::kBetter;
  RobustKernelType robust = RobustKernelType::kNone;
  std::optional<double> robust_scale;  // unset: default_scale(robust)
  LoopConsistencyConfig gate;
  long long outliers_from = -1;  // edges from this index on are known false (slam2d spoil's first_false_edge)
  bool json = false;
  bool quiet = false;
};

const char* format_name(PoseGraphFormat format) { return format == PoseGraphFormat::kToro ? "toro" : "g2o"; }

// The loop edges the back end keeps (robust weight at least 0.5) and, where the false ones are
// known, the precision and recall of that choice.
void add_loop_edge_choice(JsonObject& summary, const PoseGraph& graph, const std::vector<double>& weights,
                          const OptimizeOptions& options) {
  std::size_t loops = 0, kept = 0, true_loops = 0, true_kept = 0;
  for (std::size_t k = 0; k < graph.edges.size(); ++k) {
    if (!graph.edges[k].robust) continue;
    const bool keep = weights[k] >= 0.5;
    const bool truthful = options.outliers_from < 0 || static_cast<long long>(k) < options.outliers_from;
    ++loops;
    kept += keep ? 1 : 0;
    true_loops += truthful ? 1 : 0;
    true_kept += keep && truthful ? 1 : 0;
  }
  summary.add("loop_edges", loops).add("loop_edges_kept", kept);
  if (options.outliers_from < 0) return;
  summary.add("precision", kept > 0 ? static_cast<double>(true_kept) / static_cast<double>(kept) : 1.0);
  summary.add("recall", true_loops > 0 ? static_cast<double>(true_kept) / static_cast<double>(true_loops) : 1.0);
}

// The scale of each kernel without --robust-scale: 1, and for the truncated cost the threshold that
// held most of Vertigo's spoiled graphs (c = 2; chosen in three of four leave-one-graph-out folds).
double default_scale(RobustKernelType type) { return type == RobustKernelType::kTls ? 2.0 : 1.0; }

// The kernels by name, and gnc for tls (the method that reaches that cost).
std::map<std::string, RobustKernelType> robust_choices() {
  std::map<std::string, RobustKernelType> names = choice_map<RobustKernelType>();
  names.emplace("gnc", RobustKernelType::kTls);
  return names;
}

void run_optimize(const OptimizeOptions& options) {
  pose_graph_format_of(options.out);  // a bad extension fails before the work
  SparsePoseAdjustmentConfig config;
  config.max_iterations = options.max_iterations;
  config.loop_kernel = {.type = options.robust, .scale = options.robust_scale.value_or(default_scale(options.robust))};
  validate(config);
  const PoseGraphFile file = read_pose_graph(options.graph);
  PoseGraph graph = to_pose_graph(file);
  for (PoseGraphEdge& edge : graph.edges) edge.robust = std::abs(edge.to - edge.from) > 1;  // loop edges

  const RunClock clock;
  const GatedOptimization gated = optimize_gated(graph, config, options.initial, options.gate);
  const StartedOptimization& started = gated.optimization;
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
  summary.add("robust", std::string(choice_name(options.robust))).add("robust_scale", config.loop_kernel.scale);
  summary.add("iterations", result.iterations).add("converged", result.converged);
  if (options.robust == RobustKernelType::kTls) summary.add("gnc_rounds", result.rounds);
  add_loop_edge_choice(summary, graph, result.edge_weights, options);
  summary.add("gate", options.gate.enabled ? "pairs" : "none");
  if (options.gate.enabled) {
    summary.add("loop_edges_supported", gated.supported).add("loop_edges_admitted", gated.admitted);
    summary.add("loop_edges_refused", gated.refused).add("gate_rounds", gated.admission_rounds);
    summary.add("covariance_tests", gated.covariance_tests).add("gate_decided", gated.decided);
  }
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
  command->add_option("--robust", options->robust,
                      "Kernel on the loop edges (between nodes that are not consecutive): none, huber, cauchy, tukey, dcs "
                      "or tls (truncated least squares by graduated non-convexity; gnc names it too)")
      ->transform(CLI::CheckedTransformer(robust_choices()))
      ->default_str("none");
  command->add_option("--robust-scale", options->robust_scale,
                      "The kernel's scale k in sqrt(chi2) units (dcs: Phi = k^2; tls: the threshold c); default 1, "
                      "tls 2 (docs/methods/sparse_pose_adjustment.md, \"Graduated non-convexity\")")
      ->check(CLI::PositiveNumber);
  command->add_option("--gate", options->gate.enabled,
                      "Loop edges first gated by pairwise consistency (pairs): a closure joins the back end when another "
                      "near it along the chain agrees with it through the chain, or when the optimum of those agrees with "
                      "it (docs/methods/sparse_pose_adjustment.md, \"The consistency gate\"); none: every edge")
      ->transform(CLI::CheckedTransformer(std::map<std::string, bool>{{"pairs", true}, {"none", false}}))
      ->default_str("pairs");
  command->add_option("--gate-window", options->gate.window, "Nodes along the chain within which two closures' ends are compared")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--outliers-from", options->outliers_from,
                      "The edges from this index on (in file order) are false closures, as slam2d spoil's "
                      "first_false_edge: report the precision and recall of the loop edges kept (robust weight >= 0.5)")
      ->check(CLI::NonNegativeNumber);
  command->add_flag("--json", options->json, "Print the summary as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line (the optimisation prints none)");
  command->callback([options] { run_optimize(*options); });
}

}  // namespace slam2d::cli
