// SPDX-License-Identifier: BSD-3-Clause
// slam2d fuse --dense DENSE --sparse SPARSE --out OUT: a dense trajectory (Hector's, one pose per
// scan) bent onto a sparse, globally consistent one (graph SLAM's or the particle filter's) as the
// 2015 precise-indoor-localization pipeline does it (slam/fusion/trajectory_fusion.hpp).

#include <cstdio>
#include <filesystem>
#include <string>

#include "commands.hpp"
#include "json.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/slam/fusion/trajectory_fusion.hpp"

namespace slam2d::cli {

namespace {

struct FuseOptions {
  std::string dense;
  std::string sparse;
  std::string out;
  std::string format = "text";
  FusionConfig fusion;
  std::string alignment = "interpolated";
  bool json = false;
  bool quiet = false;
};

void run_fuse(const FuseOptions& options) {
  const TrajectoryFormat format = trajectory_format_from_name(options.format);  // checked before the work
  const Trajectory dense = read_any_trajectory(options.dense);
  const Trajectory sparse = read_any_trajectory(options.sparse);
  FusionStats stats;
  FusionConfig config = options.fusion;
  config.alignment = options.alignment == "similarity" ? FusionAlignment::kSimilarity : FusionAlignment::kInterpolated;
  const Trajectory fused = fuse_trajectories(dense, sparse, config, &stats);
  const std::filesystem::path out(options.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  write_trajectory(options.out, fused, format);

  JsonObject summary;
  summary.add("dense", options.dense).add("sparse", options.sparse).add("out", options.out);
  summary.add("poses", fused.size()).add("sparse_used", stats.sparse_used).add("segments", stats.segments);
  summary.add("blended_segments", stats.blended_segments).add("max_scale_change", stats.max_scale_change);
  if (options.json) {
    std::fputs(summary.dump().c_str(), stdout);
  } else if (!options.quiet) {
    std::fputs(summary.text().c_str(), stdout);
  }
}

}  // namespace

void add_fuse_command(CLI::App& app) {
  auto options = std::make_shared<FuseOptions>();
  CLI::App* command = app.add_subcommand(
      "fuse", "Bend a dense trajectory onto a sparse, globally consistent one (the 2015 Hector + graph pipeline)");
  command->add_option("--dense", options->dense, "Dense trajectory (one pose per scan; slam2d text or TUM)")->required();
  command->add_option("--sparse", options->sparse, "Sparse trajectory (slam2d text or TUM), stamps within the dense one's")
      ->required();
  command->add_option("--out", options->out, "Fused trajectory to write (one pose per dense pose)")->required();
  command->add_option("--alignment", options->alignment,
                      "similarity (the paper's: a similarity per segment) or interpolated (the sparse poses' rigid corrections "
                      "interpolated; measured better)")
      ->check(CLI::IsMember({"similarity", "interpolated"}))
      ->capture_default_str();
  command->add_option("--smoothing", options->fusion.correction_smoothing,
                      "s: sigma of the Gaussian average of the sparse poses' corrections (0: through every sparse pose)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  command->add_option("--format", options->format, "The output as slam2d text or tum (evo's format)")
      ->check(CLI::IsMember({"text", "tum"}));
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "No summary unless --json");
  command->callback([options] { run_fuse(*options); });
}

}  // namespace slam2d::cli
