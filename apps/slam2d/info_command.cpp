// SPDX-License-Identifier: BSD-3-Clause
// slam2d info FILE: what a CARMEN log, a map (YAML) or a pose graph (g2o/TORO) holds. For a log,
// the FLASER/RLASER geometry the reader decided, per laser and beam count, with where each value
// came from (docs/sensor_geometry.md), and the odometry's time offset against the laser that map
// and odometry would compensate by default (docs/time_offset.md).

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "json.hpp"
#include "progress.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/pose_graph_io.hpp"

namespace slam2d::cli {

namespace {

struct InfoOptions {
  std::string path;
  LogReaderOptions input;  // CARMEN geometry overrides, bag topics and frames (sensor_options.hpp)
  bool json = false;
  bool quiet = false;
};

bool ends_with_any(const std::string& path, std::initializer_list<const char*> suffixes) {
  return std::any_of(suffixes.begin(), suffixes.end(), [&](const char* s) { return path.ends_with(s); });
}

// One decided geometry: values in degrees and metres, each with its source and reason.
JsonObject geometry_json(const OldLaserGeometry& geometry) {
  JsonObject json;
  json.add("laser", geometry.rear ? "RLASER" : "FLASER").add("beams", geometry.beams).add("scans", geometry.scans);
  json.add("first_line", geometry.first_line);
  const double last_beam = geometry.angle_min.value +
                           static_cast<double>(geometry.beams > 0 ? geometry.beams - 1 : 0) * geometry.angle_increment.value;
  json.add("fov_deg", rad_to_deg(geometry.field_of_view.value));
  json.add("angle_min_deg", rad_to_deg(geometry.angle_min.value));
  json.add("angle_increment_deg", rad_to_deg(geometry.angle_increment.value));
  json.add("last_beam_deg", rad_to_deg(last_beam)).add("range_max", geometry.range_max.value);
  const std::pair<const char*, const GeometryValue*> values[] = {{"fov", &geometry.field_of_view},
                                                                 {"angle_min", &geometry.angle_min},
                                                                 {"angle_increment", &geometry.angle_increment},
                                                                 {"range_max", &geometry.range_max}};
  for (const auto& [name, value] : values) {
    json.add(std::string(name) + "_source", to_string(value->source));
    json.add(std::string(name) + "_reason", value->reason);
  }
  json.add("readings_at_range_max", geometry.readings_at_range_max);
  json.add("readings_at_range_max_fraction",
           geometry.readings > 0 ? static_cast<double>(geometry.readings_at_range_max) / static_cast<double>(geometry.readings)
                                 : 0.0);
  json.add("warnings", geometry.warnings);
  return json;
}

// "front" and "rear", or "front_361" etc. when a laser has several geometries (beam counts, PARAM changes).
JsonObject geometries_json(const std::vector<OldLaserGeometry>& geometries) {
  JsonObject json;
  for (const OldLaserGeometry& geometry : geometries) {
    const std::size_t same_laser = static_cast<std::size_t>(std::count_if(
        geometries.begin(), geometries.end(), [&](const OldLaserGeometry& g) { return g.rear == geometry.rear; }));
    const std::size_t same_beams = static_cast<std::size_t>(std::count_if(
        geometries.begin(), geometries.end(),
        [&](const OldLaserGeometry& g) { return g.rear == geometry.rear && g.beams == geometry.beams; }));
    std::string key = geometry.rear ? "rear" : "front";
    if (same_laser > 1) key += "_" + std::to_string(geometry.beams);
    if (same_beams > 1) key += "_from_line_" + std::to_string(geometry.first_line);
    json.add(key, geometry_json(geometry));
  }
  return json;
}

JsonObject log_info(const InfoOptions& options) {
  CarmenReader reader(options.path, options.input.carmen);
  Progress progress("info", options.quiet);
  std::map<std::size_t, std::size_t> beam_counts;  // beams -> scans
  std::map<std::string, std::size_t> laser_types;
  std::size_t scans = 0;
  double fov = 0.0, largest_reading = 0.0, range_max = 0.0;
  std::optional<double> first_scan, last_scan;
  std::vector<SensorMessage> messages;  // for the odometry time offset
  while (auto message = reader.next()) {
    messages.push_back(*message);
    if (const auto* laser = std::get_if<LaserMessage>(&*message)) {
      ++scans;
      ++beam_counts[laser->scan.size()];
      ++laser_types[laser->type];
      fov = std::max(fov, laser->field_of_view);
      range_max = std::max(range_max, laser->scan.range_max);
      for (double r : laser->scan.ranges) largest_reading = std::max(largest_reading, r);
      if (!first_scan) first_scan = laser->scan.stamp;
      last_scan = laser->scan.stamp;
      if (scans % 1024 == 0) progress.update(reader.progress(), fmt::format("{} scans", scans));
    }
  }
  progress.finish();
  const CarmenStats& stats = reader.stats();
  const double duration = scans > 0 ? *last_scan - *first_scan : 0.0;
  const auto most_common = std::max_element(beam_counts.begin(), beam_counts.end(),
                                            [](const auto& a, const auto& b) { return a.second < b.second; });
  JsonObject json;
  json.add("file", options.path).add("kind", "carmen_log").add("scans", scans);
  json.add("beams", beam_counts.empty() ? std::size_t{0} : most_common->first);
  json.add("fov_deg", rad_to_deg(fov)).add("max_range", largest_reading).add("range_max", range_max);
  json.add("rate_hz", duration > 0.0 ? std::optional<double>((scans - 1) / duration) : std::nullopt);
  json.add("duration_s", duration).add("odom_messages", stats.odometry_messages);
  json.add("true_pose_messages", stats.true_pose_messages);
  json.add("backwards_timestamps", stats.backwards_laser_timestamps);
  json.add("backwards_timestamps_all_messages", stats.backwards_timestamps);
  json.add("skipped_lines", stats.skipped_lines);
  json.add("odometry_steps_reversed", stats.odometry_steps_reversed);
  JsonObject types;
  for (const auto& [type, count] : laser_types) types.add(type, count);
  json.add("laser_types", types);
  JsonObject skipped;
  for (const auto& [type, count] : stats.skipped_types) skipped.add(type, count);
  json.add("skipped_types", skipped);
  json.add("geometry", geometries_json(stats.old_laser_geometries));
  json.merge(odometry_time_offset_json(estimate_odometry_time_offset_choice(messages)));
  return json;
}

// A bag: its topics (type, count, rate), what the assembly uses (topics, frames, the laser's
// mounting) and the scans it gives.
JsonObject bag_info(const InfoOptions& options) {
  LogReader reader(options.path, options.input);
  Progress progress("info", options.quiet);
  std::map<std::size_t, std::size_t> beam_counts;  // beams -> scans
  std::size_t scans = 0, odometry = 0, without_pose = 0;
  double fov = 0.0;
  std::optional<double> first_scan, last_scan;
  std::vector<SensorMessage> messages;  // for the odometry time offset
  while (auto message = reader.next()) {
    messages.push_back(*message);
    if (const auto* laser = std::get_if<LaserMessage>(&*message)) {
      ++scans;
      ++beam_counts[laser->scan.size()];
      fov = std::max(fov, laser->field_of_view);
      if (!laser->has_poses) ++without_pose;
      if (!first_scan) first_scan = laser->scan.stamp;
      last_scan = laser->scan.stamp;
      if (scans % 1024 == 0) progress.update(reader.progress(), fmt::format("{} scans", scans));
    } else if (std::holds_alternative<OdometryMessage>(*message)) {
      ++odometry;
    }
  }
  progress.finish();
  const BagLogReader& bag = *reader.bag();
  const BagChoice& choice = bag.choice();
  JsonObject json;
  json.add("file", options.path).add("kind", "bag").add("format", log_format_name(reader.format()));
  JsonObject topics;
  for (const BagTopic& topic : bag.topics()) {
    const double span = topic.last_stamp - topic.first_stamp;
    JsonObject entry;
    entry.add("type", topic.type).add("count", topic.count);
    entry.add("rate_hz", topic.count > 1 && span > 0.0 ? std::optional<double>((topic.count - 1) / span) : std::nullopt);
    topics.add(topic.name, entry);
  }
  json.add("topics", topics);
  JsonObject uses;
  uses.add("scan_topic", choice.scan_topic).add("odom_topic", choice.odom_topic).add("imu_topic", choice.imu_topic);
  uses.add("base_frame", choice.base_frame).add("odom_frame", choice.odom_frame).add("laser_frame", choice.laser_frame);
  if (choice.T_base_laser) {
    uses.add("laser_x", choice.T_base_laser->x()).add("laser_y", choice.T_base_laser->y());
    uses.add("laser_yaw_deg", rad_to_deg(choice.T_base_laser->theta()));
  } else {
    uses.add_null("laser_x");
  }
  json.add("uses", uses);
  const double duration = scans > 0 ? *last_scan - *first_scan : 0.0;
  const auto most_common = std::max_element(beam_counts.begin(), beam_counts.end(),
                                            [](const auto& a, const auto& b) { return a.second < b.second; });
  json.add("scans", scans).add("beams", beam_counts.empty() ? std::size_t{0} : most_common->first);
  json.add("fov_deg", rad_to_deg(fov)).add("duration_s", duration);
  json.add("rate_hz", duration > 0.0 ? std::optional<double>((scans - 1) / duration) : std::nullopt);
  json.add("odom_messages", odometry).add("scans_without_odometry", without_pose);
  json.merge(odometry_time_offset_json(estimate_odometry_time_offset_choice(messages)));
  json.add("warnings", bag.warnings());
  return json;
}

JsonObject map_info(const InfoOptions& options) {
  const MapMetadata metadata = read_map_metadata(options.path);
  const OccupancyMap map = read_map(options.path);
  std::size_t occupied = 0, free = 0, unknown = 0;
  for (const auto cell : map.cells) {
    if (cell == OccupancyMap::kUnknown) ++unknown;
    else if (cell >= 50) ++occupied;
    else ++free;
  }
  JsonObject json;
  json.add("file", options.path).add("kind", "map").add("image", metadata.image);
  json.add("width", map.width).add("height", map.height).add("resolution", map.resolution);
  json.add("size_x_m", map.width * map.resolution).add("size_y_m", map.height * map.resolution);
  json.add("origin_x", map.origin.x()).add("origin_y", map.origin.y()).add("origin_yaw", map.origin.theta());
  json.add("occupied_cells", occupied).add("free_cells", free).add("unknown_cells", unknown);
  return json;
}

JsonObject graph_info(const InfoOptions& options) {
  const PoseGraphFile graph = read_pose_graph(options.path);
  JsonObject json;
  json.add("file", options.path).add("kind", "pose_graph");
  json.add("format", graph.format == PoseGraphFormat::kG2o ? "g2o" : "toro");
  json.add("vertices", graph.vertices.size()).add("edges", graph.edges.size());
  json.add("fixed", graph.fixed.size()).add("skipped_lines", graph.skipped_lines);
  return json;
}

void run_info(const InfoOptions& options) {
  JsonObject json;
  if (detect_log_format(options.path) != LogFormat::kCarmen) {
    json = bag_info(options);
  } else if (ends_with_any(options.path, {".yaml", ".yml"})) {
    json = map_info(options);
  } else if (ends_with_any(options.path, {".g2o", ".g2o.gz", ".graph", ".graph.gz", ".toro"})) {
    json = graph_info(options);
  } else {
    json = log_info(options);
  }
  std::fputs(options.json ? json.dump().c_str() : json.text().c_str(), stdout);
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* command = app.add_subcommand("info", "Summarise a log (CARMEN, ROS 1 bag, MCAP, rosbag2 folder), a map (.yaml) or a pose graph (.g2o, .graph)");
  command->add_option("file", options->path, "CARMEN log (plain or .gz), ROS 1 bag, MCAP file, rosbag2 folder, map YAML, or g2o/TORO graph")->required();
  add_sensor_options(command, options->input);
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_info(*options); });
}

}  // namespace slam2d::cli
