#pragma once
// The mapping job behind `slam2d map` (and `slam2d demo`): read a log, estimate the trajectory
// with the chosen method, build the occupancy grid, write the outputs.

#include <cstdint>
#include <optional>
#include <string>

#include "json.hpp"
#include "slam2d/core/occupancy_map.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/io/carmen.hpp"

namespace slam2d::cli {

struct MapJobOptions {
  std::string log;                  // CARMEN log, plain or .gz
  std::string out_dir;              // written: map.pgm, map.yaml, map.png, trajectory.txt, summary.json
  std::string method = "odometry";  // odometry, hector, graph, rbpf
  double resolution = 0.05;         // m per cell
  bool no_odometry = false;         // hector, graph: ignore the log's odometry (last pose / constant velocity)
  int levels = 3;                   // hector: map pyramid levels, in [1, 16]
  int particles = 30;               // rbpf: number of particles, in [1, 10000]
  std::uint64_t seed = 1;           // rbpf: seed of every random draw (same log + seed, same result)
  int threads = 0;                  // rbpf: threads for the particles, in [0, 256] (0: all hardware threads); same result
  bool quiet = false;               // no progress line
  CarmenReaderOptions geometry;     // FLASER/RLASER geometry overrides (sensor_options.hpp); unset: PARAM, else convention
};

struct MapJobResult {
  OccupancyMap map;
  Trajectory trajectory;  // one pose per scan used, in log order
  JsonObject summary;     // what summary.json holds
};

/// Runs the job and writes its outputs; nothing is written if the log cannot be read to the end.
MapJobResult run_map_job(const MapJobOptions& options);

/// The methods `--method` accepts.
const std::vector<std::string>& map_methods();

}  // namespace slam2d::cli
