// SPDX-License-Identifier: BSD-3-Clause
// slam2d map LOG --method METHOD --out DIR: build a map and a trajectory from a log.

#include <cstdio>

#include "commands.hpp"
#include "map_job.hpp"
#include "sensor_options.hpp"

namespace slam2d::cli {

void add_map_command(CLI::App& app) {
  auto options = std::make_shared<MapJobOptions>();
  auto json = std::make_shared<bool>(false);
  CLI::App* command = app.add_subcommand("map", "Build an occupancy map and a trajectory from a log");
  command->add_option("log", options->log, "CARMEN log (plain or .gz), ROS 1 bag, MCAP file or rosbag2 folder")->required();
  command->add_option("--out", options->out_dir, "Output folder: map.pgm, map.yaml, map.png, trajectory.txt, summary.json")
      ->required();
  command->add_option("--method", options->method,
                      "Mapping method; hector+graph and hector+rbpf run the 2015 chain: Hector on the laser alone as the "
                      "odometry of graph SLAM or the particle filter on 3 scans a second, their trajectory fused into Hector's")
      ->check(CLI::IsMember(map_methods()))
      ->capture_default_str();
  command->add_option("--config", options->config,
                      "hector, graph, rbpf: a method preset (configs/<method>.yaml; `slam2d config dump METHOD` prints the defaults); the flags below override it")
      ->check(CLI::ExistingFile);
  command->add_option("--resolution", options->resolution, "m per map cell (default: the method's, 0.05)");
  add_sensor_options(command, options->input);
  command->add_option("--odometry-source", options->odometry_source,
                      "The odometry each scan carries into the method: log (the log's wheel odometry), none (hector: the last pose; "
                      "graph: constant velocity; rbpf: as hector), hector (Hector SLAM on the laser alone, jumps "
                      "smoothed: the 2015 pipeline), or a trajectory file (slam2d text or TUM) interpolated at each scan")
      ->capture_default_str();
  command->add_flag("--no-odometry", options->no_odometry, "The same as --odometry-source none");
  command->add_flag("!--no-odometry-smoothing", options->odometry_smoothing,
                    "Keep the method's per-scan poses as they are (default: smoothed with the odometry, each weighed "
                    "by the noise the data shows; docs/fusion_by_uncertainty.md)");
  command->add_flag("--smoothing-third-stream", options->smoothing_third_stream,
                    "Estimate the smoothing's noises with PL-ICP scan odometry as a third stream: tells a slow error "
                    "of the method (a noisy laser) from the odometry's drift (docs/fusion_by_uncertainty.md)");
  add_odometry_time_offset_option(command, options->odometry_time_offset);
  command->add_option("--scan-rate", options->scan_rate,
                      "Hz: the method sees one scan per 1/rate s (the time-based subset; a standing robot still contributes "
                      "scans); default: every scan, and 3 Hz for the sparse method of hector+graph and hector+rbpf");
  command->add_option("--levels", options->levels, "hector: map pyramid levels (default 3)")->check(CLI::Range(1, 16));
  command->add_option("--particles", options->particles, "rbpf: number of particles (default 30)")->check(CLI::Range(1, 10000));
  command->add_option("--seed", options->seed, "rbpf: random seed (default 1; same log and seed give the same result)");
  command->add_option("--threads", options->threads,
                      "rbpf: threads for the particles (default 0: all hardware threads; 1: serial); the result does not depend on it")
      ->check(CLI::Range(0, 256));
  command->add_option("--reference", options->reference,
                      "A trajectory (slam2d text or TUM, e.g. the ground truth) drawn in map.png under the run's, aligned onto it")
      ->check(CLI::ExistingFile);
  command->add_option("--format", options->trajectory_format, "trajectory.txt as slam2d text (t x y theta) or tum (evo's format)")
      ->check(CLI::IsMember({"text", "tum"}))
      ->capture_default_str();
  command->add_option("--mcap", options->mcap,
                      "Also write the run for Foxglove: map, path, poses, scans (and in the map frame), tf (MCAP, ROS 2 types)");
  command->add_option("--trajectory-frame", options->trajectory_frame,
                      "robot: the robot's (base frame's) pose; sensor: the laser's (the robot's pose times the laser's mounting)")
      ->check(CLI::IsMember({"robot", "sensor"}))
      ->capture_default_str();
  command->add_flag("--json", *json, "Print the summary as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options, json] {
    const MapJobResult result = run_map_job(*options);
    std::fputs(*json ? result.summary.dump().c_str() : result.summary.text().c_str(), stdout);
  });
}

}  // namespace slam2d::cli
