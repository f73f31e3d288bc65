// SPDX-License-Identifier: BSD-3-Clause
// slam2d report's data: each run folder's map, trajectory, summary and pose graph, the errors
// against the ground truth, and the scan replay of the log, gathered and written as one JSON blob.

#include "report_data.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <span>
#include <unordered_map>
#include <variant>

#include "json.hpp"
#include "report_html.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/pose_graph_file.hpp"
#include "slam2d/eval/ate.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/eval/statistics.hpp"
#include "slam2d/grid/render.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/io/trajectory_io.hpp"

namespace slam2d::cli {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// Reading a run folder

std::string base64(std::span<const std::uint8_t> bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t word = static_cast<std::uint32_t>(bytes[i]) << 16;
    if (n > 1) word |= static_cast<std::uint32_t>(bytes[i + 1]) << 8;
    if (n > 2) word |= bytes[i + 2];
    for (std::size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(word >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

ReportMap read_report_map(const std::string& yaml_path) {
  const OccupancyMap map = crop_to_content(read_map(yaml_path), 10);
  check(std::abs(map.origin.theta()) < 1e-9, yaml_path + ": a map with a rotated origin cannot be shown");
  ReportMap out;
  out.png_data_uri = "data:image/png;base64," + base64(encode_png(render_map(map, {})));
  out.width = map.width;
  out.height = map.height;
  out.origin_x = map.origin.x();
  out.origin_y = map.origin.y();
  out.resolution = map.resolution;
  return out;
}

/// A YAML node (JSON is YAML) as JSON: quoted scalars stay strings, plain ones that read as
/// numbers or booleans become those.
std::string yaml_to_json(const YAML::Node& node) {
  if (node.IsMap()) {
    std::string out = "{";
    for (auto it = node.begin(); it != node.end(); ++it) {
      out += (out.size() > 1 ? "," : "") + json_string(it->first.Scalar()) + ":" + yaml_to_json(it->second);
    }
    return out + "}";
  }
  if (node.IsSequence()) {
    std::string out = "[";
    for (std::size_t i = 0; i < node.size(); ++i) out += (i == 0 ? "" : ",") + yaml_to_json(node[i]);
    return out + "]";
  }
  if (!node.IsScalar() || node.IsNull()) return "null";
  const std::string& text = node.Scalar();
  if (node.Tag() == "!") return json_string(text);
  if (text == "true" || text == "false") return text;
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error == std::errc() && end == text.data() + text.size()) return json_number(value);
  return json_string(text);
}

std::optional<double> summary_number(const YAML::Node& summary, const char* key) {
  if (!summary.IsMap() || !summary[key] || !summary[key].IsScalar()) return std::nullopt;
  try {
    return summary[key].as<double>();
  } catch (const YAML::Exception&) {
    return std::nullopt;
  }
}

void read_summary(const std::string& path, ReportRun& run) {
  if (!fs::exists(path)) return;
  YAML::Node summary;
  try {
    summary = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw ParseError(path, static_cast<std::size_t>(e.mark.line + 1), "not valid JSON: " + e.msg);
  }
  check(summary.IsMap(), path + ": not a JSON object");
  run.summary_json = yaml_to_json(summary);
  run.cpu_s = summary_number(summary, "cpu_s");
  run.realtime_factor = summary_number(summary, "realtime_factor");
  run.peak_rss_mb = summary_number(summary, "peak_rss_mb");
}

std::vector<ReportSegment> loop_closures(const PoseGraphFile& graph) {
  std::unordered_map<int, const GraphVertex*> vertices;
  for (const GraphVertex& vertex : graph.vertices) vertices[vertex.id] = &vertex;
  std::vector<ReportSegment> segments;
  for (const GraphEdge& edge : graph.edges) {
    if (std::abs(edge.to - edge.from) == 1) continue;
    const auto from = vertices.find(edge.from);
    const auto to = vertices.find(edge.to);
    if (from == vertices.end() || to == vertices.end()) continue;
    segments.push_back({from->second->pose.x(), from->second->pose.y(), to->second->pose.x(), to->second->pose.y()});
  }
  return segments;
}

// ---------------------------------------------------------------------------------------------
// Errors against the ground truth

std::vector<ReportError> relation_errors(const Trajectory& estimate, const std::vector<Relation>& relations,
                                         double tolerance) {
  const RelationErrorResult result = relation_error(estimate, relations, {.stamp_tolerance = tolerance});
  std::vector<ReportError> errors;
  for (const RelationError& e : result.errors) {
    errors.push_back({relations[e.relation_index].stamp_from, e.T_world_from.x(), e.T_world_from.y(), e.translation});
  }
  return errors;
}

std::vector<ReportError> pose_errors(const Trajectory& estimate, const Trajectory& reference, double tolerance) {
  const AteResult ate = absolute_trajectory_error(estimate, reference, {.stamp_tolerance = tolerance});
  std::vector<ReportError> errors;
  for (std::size_t i = 0; i < ate.errors.size(); ++i) {
    const StampedPose& pose = estimate[ate.estimate_indices[i]];
    errors.push_back({pose.stamp, pose.pose.x(), pose.pose.y(), ate.errors[i]});
  }
  return errors;
}

void summarise_errors(ReportRun& run) {
  std::sort(run.errors.begin(), run.errors.end(), [](const auto& a, const auto& b) { return a.stamp < b.stamp; });
  std::vector<double> values;
  for (const ReportError& e : run.errors) values.push_back(e.error);
  const ErrorStatistics statistics = compute_statistics(values);
  run.error_mean = statistics.mean;
  run.error_max = statistics.max;
  run.error_median = median(values);
  run.error_rmse = root_mean_square(values);
}

struct GroundTruth {
  std::optional<std::vector<Relation>> relations;
  std::optional<Trajectory> reference;
};

ReportRun read_run(const std::string& dir, const GroundTruth& truth, double tolerance) {
  check(fs::is_directory(dir), dir + ": no such run folder");
  ReportRun run;
  run.dir = dir;
  run.name = fs::path(dir).lexically_normal().filename().string();
  if (run.name.empty()) run.name = fs::path(dir).lexically_normal().parent_path().filename().string();
  run.trajectory = read_any_trajectory((fs::path(dir) / "trajectory.txt").string());
  run.summary_json = "{}";
  read_summary((fs::path(dir) / "summary.json").string(), run);
  const fs::path map_yaml = fs::path(dir) / "map.yaml";
  if (fs::exists(map_yaml)) run.map = read_report_map(map_yaml.string());
  const fs::path graph = fs::path(dir) / "graph.g2o";
  if (fs::exists(graph)) run.loop_closures = loop_closures(read_pose_graph(graph.string()));
  if (truth.relations) run.errors = relation_errors(run.trajectory, *truth.relations, tolerance);
  if (truth.reference) run.errors = pose_errors(run.trajectory, *truth.reference, tolerance);
  summarise_errors(run);
  return run;
}

// ---------------------------------------------------------------------------------------------
// Scan replay

/// Evenly spaced indices of at most `count` of `n` items.
std::vector<std::size_t> evenly(std::size_t n, std::size_t count) {
  std::vector<std::size_t> picked;
  if (n == 0 || count == 0) return picked;
  const std::size_t k = std::min(n, count);
  for (std::size_t i = 0; i < k; ++i) picked.push_back(k == 1 ? 0 : i * (n - 1) / (k - 1));
  return picked;
}

ReplayScan replay_scan(const LaserScan& scan, const StampedPose& pose, std::size_t max_points) {
  ReplayScan out{.stamp = pose.stamp, .x = pose.pose.x(), .y = pose.pose.y(), .theta = pose.pose.theta(), .points_cm = {}};
  const ScanPoints points = to_point_cloud(scan, ScanFrame::kRobot);
  const std::size_t n = points.cloud.size();
  const Eigen::Matrix2d rotation = pose.pose.rotation();
  for (std::size_t i : evenly(n, max_points)) {
    const Eigen::Vector2d offset = rotation * points.cloud.points[i];
    out.points_cm.push_back(static_cast<int>(std::lround(offset.x() * 100.0)));
    out.points_cm.push_back(static_cast<int>(std::lround(offset.y() * 100.0)));
  }
  return out;
}

/// The log's scans at (up to max_scans) evenly spaced poses of the trajectory, in the map frame.
std::vector<ReplayScan> read_replay(const ReportInputs& inputs, const Trajectory& trajectory, std::size_t& log_scans) {
  std::vector<bool> wanted(trajectory.size(), false);
  for (std::size_t i : evenly(trajectory.size(), inputs.max_replay_scans)) wanted[i] = true;
  const StampIndex index(trajectory);
  std::vector<ReplayScan> replay;
  LogReader reader(inputs.log, inputs.log_options);
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr) continue;
    ++log_scans;
    const std::optional<std::size_t> i = index.nearest(laser->scan.stamp, inputs.stamp_tolerance);
    if (!i || !wanted[*i]) continue;
    wanted[*i] = false;
    replay.push_back(replay_scan(laser->scan, trajectory[*i], inputs.max_replay_points));
  }
  std::sort(replay.begin(), replay.end(), [](const auto& a, const auto& b) { return a.stamp < b.stamp; });
  return replay;
}

// ---------------------------------------------------------------------------------------------
// JSON

/// A number rounded to `decimals` places, shortest form.
std::string rounded(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return json_number(std::round(value * scale) / scale);
}

std::string optional_number(const std::optional<double>& value, int decimals) {
  return value ? rounded(*value, decimals) : "null";
}

template <typename T, typename Format>
std::string array(const std::vector<T>& values, Format&& format) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i == 0 ? "" : ",") + format(values[i]);
  return out + "]";
}

std::string numbers(const std::vector<double>& values, int decimals) {
  return array(values, [decimals](double v) { return rounded(v, decimals); });
}

std::string map_json(const ReportMap& map) {
  return "{\"png\":" + json_string(map.png_data_uri) + ",\"width\":" + std::to_string(map.width) +
         ",\"height\":" + std::to_string(map.height) + ",\"origin\":[" + rounded(map.origin_x, 4) + "," +
         rounded(map.origin_y, 4) + "],\"resolution\":" + json_number(map.resolution) + "}";
}

std::string errors_json(const std::vector<ReportError>& errors) {
  std::vector<double> t, x, y, e;
  for (const ReportError& error : errors) t.push_back(error.stamp), x.push_back(error.x), y.push_back(error.y), e.push_back(error.error);
  return "{\"t\":" + numbers(t, 3) + ",\"x\":" + numbers(x, 2) + ",\"y\":" + numbers(y, 2) + ",\"e\":" + numbers(e, 4) + "}";
}

std::string run_json(const ReportRun& run) {
  std::string out = "{\"name\":" + json_string(run.name) + ",\"dir\":" + json_string(run.dir);
  out += ",\"summary\":" + run.summary_json;
  out += ",\"cpu_s\":" + optional_number(run.cpu_s, 3) + ",\"realtime_factor\":" + optional_number(run.realtime_factor, 3) +
         ",\"peak_rss_mb\":" + optional_number(run.peak_rss_mb, 1);
  out += ",\"map\":" + (run.map ? map_json(*run.map) : std::string("null"));
  std::vector<double> t, x, y, theta;
  for (const StampedPose& pose : run.trajectory) {
    t.push_back(pose.stamp), x.push_back(pose.pose.x()), y.push_back(pose.pose.y()), theta.push_back(pose.pose.theta());
  }
  out += ",\"trajectory\":{\"t\":" + numbers(t, 3) + ",\"x\":" + numbers(x, 2) + ",\"y\":" + numbers(y, 2) +
         ",\"theta\":" + numbers(theta, 3) + "}";
  out += ",\"overlay\":{\"x\":" + numbers(run.overlay_xs, 2) + ",\"y\":" + numbers(run.overlay_ys, 2) + "}";
  out += ",\"errors\":" + errors_json(run.errors);
  out += ",\"error_stats\":{\"mean\":" + rounded(run.error_mean, 4) + ",\"median\":" + rounded(run.error_median, 4) +
         ",\"max\":" + rounded(run.error_max, 4) + ",\"rmse\":" + rounded(run.error_rmse, 4) +
         ",\"count\":" + std::to_string(run.errors.size()) + "}";
  out += ",\"loop_closures\":" + array(run.loop_closures, [](const ReportSegment& s) {
           return "[" + rounded(s.x0, 2) + "," + rounded(s.y0, 2) + "," + rounded(s.x1, 2) + "," + rounded(s.y1, 2) + "]";
         });
  return out + "}";
}

std::string replay_json(const ReplayScan& scan) {
  return "[" + rounded(scan.stamp, 3) + "," + rounded(scan.x, 2) + "," + rounded(scan.y, 2) + "," + rounded(scan.theta, 3) +
         "," + array(scan.points_cm, [](int v) { return std::to_string(v); }) + "]";
}

/// The run's positions moved onto the base run's frame by the rigid motion that best aligns the
/// poses of equal stamps (runs of one log in different frames, e.g. odometry's); unmoved when
/// fewer than two stamps match.
void align_onto(ReportRun& run, const Trajectory& first, double tolerance) {
  const StampIndex index(first);
  std::vector<Eigen::Vector2d> source, target;
  for (const StampedPose& pose : run.trajectory) {
    if (const auto j = index.nearest(pose.stamp, tolerance)) {
      source.push_back(pose.pose.translation());
      target.push_back(first[*j].pose.translation());
    }
  }
  const SE2 T = source.size() >= 2 ? align_rigid_2d(source, target) : SE2();
  for (const StampedPose& pose : run.trajectory) {
    const Eigen::Vector2d p = T * pose.pose.translation();
    run.overlay_xs.push_back(p.x());
    run.overlay_ys.push_back(p.y());
  }
}

}  // namespace

ReportData collect_report(const ReportInputs& inputs) {
  check(!inputs.run_dirs.empty(), "report: give at least one RUN_DIR");
  GroundTruth truth;
  ReportData data;
  if (!inputs.relations.empty()) truth.relations = read_relations(inputs.relations), data.error_kind = "relations";
  if (!inputs.reference.empty()) truth.reference = read_any_trajectory(inputs.reference), data.error_kind = "ate";
  for (const std::string& dir : inputs.run_dirs) data.runs.push_back(read_run(dir, truth, inputs.stamp_tolerance));
  if (!data.error_kind.empty()) {
    const auto best = std::min_element(data.runs.begin(), data.runs.end(), [](const ReportRun& a, const ReportRun& b) {
      return !a.errors.empty() && (b.errors.empty() || a.error_mean < b.error_mean);
    });
    data.base = static_cast<std::size_t>(best - data.runs.begin());
  }
  const Trajectory& base = data.runs[data.base].trajectory;
  for (ReportRun& run : data.runs) align_onto(run, base, inputs.stamp_tolerance);
  if (!inputs.log.empty()) data.replay = read_replay(inputs, base, data.log_scans);
  return data;
}

std::string report_json(const ReportData& data) {
  std::string out = "{\"version\":1,\"error_kind\":" + json_string(data.error_kind) + ",\"base\":" + std::to_string(data.base);
  out += ",\"runs\":" + array(data.runs, run_json);
  out += ",\"replay\":{\"log_scans\":" + std::to_string(data.log_scans) + ",\"scans\":" + array(data.replay, replay_json) + "}";
  out += "}";
  std::string safe;
  safe.reserve(out.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (out[i] == '<' && i + 1 < out.size() && out[i + 1] == '/') safe += "<\\";
    else safe += out[i];
  }
  return safe;
}

WrittenReport write_report(const ReportData& data, const std::string& out_dir) {
  constexpr std::string_view kDataPlaceholder = "\"@REPORT_DATA@\"";
  const std::string_view page = kReportHtml;
  const std::size_t at = page.find(kDataPlaceholder);
  check(at != std::string_view::npos, "report: the HTML template has no data placeholder");
  std::string html(page.substr(0, at));
  html += report_json(data);
  html += page.substr(at + kDataPlaceholder.size());
  fs::create_directories(out_dir);
  const std::string path = (fs::path(out_dir) / "index.html").string();
  write_file_atomically(path, html);
  return {path, html.size()};
}

}  // namespace slam2d::cli
