#include "map_job.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <filesystem>

#include "progress.hpp"
#include "run_stats.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/grid/render.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/trajectory_io.hpp"

namespace slam2d::cli {

namespace {

struct MappingRun {
  OccupancyMap map;
  Trajectory trajectory;
  std::size_t backwards_timestamps = 0;
  std::size_t skipped_lines = 0;
  double data_duration = 0.0;  // s, last scan stamp minus first, in file order
};

// Odometry mapping: every scan is placed at the robot's odometry pose at its stamp.
MappingRun map_with_odometry(const MapJobOptions& options) {
  CarmenReader reader(options.log);
  OccupancyGrid grid(OccupancyGridConfig{.resolution = options.resolution});
  Progress progress("map", options.quiet);
  MappingRun run;
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr) continue;
    if (!laser->has_poses) {
      throw ParseError(reader.path(), laser->line, laser->type + " carries no odometry pose; the odometry method needs FLASER, RLASER or ROBOTLASER1");
    }
    grid.integrate_scan(laser->scan, laser->odom_pose);
    run.trajectory.push_back(laser->scan.stamp, laser->odom_pose);
    if (run.trajectory.size() % 256 == 0) {
      progress.update(reader.progress(), fmt::format("{} scans", run.trajectory.size()));
    }
  }
  progress.finish();
  check(!run.trajectory.empty(), reader.path() + ": no laser scans in the log");
  run.map = grid.to_occupancy_map();
  run.backwards_timestamps = reader.stats().backwards_laser_timestamps;
  run.skipped_lines = reader.stats().skipped_lines;
  run.data_duration = run.trajectory.back().stamp - run.trajectory.front().stamp;
  return run;
}

std::vector<SE2> poses_of(const Trajectory& trajectory) {
  std::vector<SE2> poses;
  poses.reserve(trajectory.size());
  for (const auto& stamped : trajectory) poses.push_back(stamped.pose);
  return poses;
}

void write_outputs(const std::filesystem::path& dir, const MappingRun& run, const JsonObject& summary) {
  std::filesystem::create_directories(dir);
  write_map((dir / "map.yaml").string(), run.map, "map.pgm");
  write_png((dir / "map.png").string(), render_map(run.map, poses_of(run.trajectory)));
  write_trajectory((dir / "trajectory.txt").string(), run.trajectory);
  write_file_atomically((dir / "summary.json").string(), summary.dump());
}

}  // namespace

const std::vector<std::string>& map_methods() {
  static const std::vector<std::string> methods{"odometry"};
  return methods;
}

MapJobResult run_map_job(const MapJobOptions& options) {
  const auto& methods = map_methods();
  check(std::find(methods.begin(), methods.end(), options.method) != methods.end(),
        "map: unknown method '" + options.method + "' (known: odometry)");
  check(options.resolution > 0.0 && options.resolution <= 10.0, "map: --resolution must be in (0, 10] m");
  const RunClock clock;
  MappingRun run = map_with_odometry(options);
  const double cpu = clock.cpu_seconds();
  const double wall = clock.wall_seconds();

  JsonObject summary;
  summary.add("method", options.method).add("log", options.log).add("scans", run.trajectory.size());
  summary.add("data_duration_s", run.data_duration).add("cpu_s", cpu).add("wall_s", wall);
  summary.add("realtime_factor", cpu > 0.0 ? std::optional<double>(run.data_duration / cpu) : std::nullopt);
  summary.add("us_per_scan", 1e6 * cpu / static_cast<double>(run.trajectory.size()));
  summary.add("resolution", options.resolution).add("map_width", run.map.width).add("map_height", run.map.height);
  summary.add("backwards_timestamps", run.backwards_timestamps).add("skipped_lines", run.skipped_lines);
  summary.add("peak_rss_mb", peak_rss_mb());
  write_outputs(options.out_dir, run, summary);
  return {std::move(run.map), std::move(run.trajectory), std::move(summary)};
}

}  // namespace slam2d::cli
