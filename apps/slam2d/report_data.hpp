// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What `slam2d report` shows, gathered from the run folders (`slam2d map --out RUN_DIR`), the
// ground truth and the log, and its serialisation as the one JSON blob the HTML page draws from.
// Positions are in metres rounded to cm, scan points in integer cm (see docs/report.md).

#include <optional>
#include <string>
#include <vector>

#include "slam2d/core/trajectory.hpp"
#include "slam2d/io/log_reader.hpp"

namespace slam2d::cli {

/// The occupancy grid as a PNG (data URI) and where it lies: origin of its lower-left pixel, m per pixel.
struct ReportMap {
  std::string png_data_uri;
  int width = 0;
  int height = 0;
  double origin_x = 0.0;
  double origin_y = 0.0;
  double resolution = 0.05;
};

/// One error sample: where (the estimate's position, in the run's map frame) and when it is.
struct ReportError {
  double stamp = 0.0;
  double x = 0.0;
  double y = 0.0;
  double error = 0.0;  // m: a relation's translational error, or a pose's ATE
};

struct ReportSegment {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
};

struct ReportRun {
  std::string name;           // the run folder's name
  std::string dir;
  std::string summary_json;   // summary.json re-encoded as JSON ("{}" when absent)
  std::optional<double> cpu_s, realtime_factor, peak_rss_mb;
  std::optional<ReportMap> map;
  Trajectory trajectory;
  std::vector<double> overlay_xs, overlay_ys;  // its positions aligned onto the base run's frame
  std::vector<ReportError> errors;             // in time order
  std::vector<ReportSegment> loop_closures;    // graph SLAM: edges between non-consecutive vertices
  double error_mean = 0.0, error_median = 0.0, error_max = 0.0, error_rmse = 0.0;
};

/// A scan of the replay: the robot pose (the base run's trajectory) and the end points in the map frame.
struct ReplayScan {
  double stamp = 0.0;
  double x = 0.0, y = 0.0, theta = 0.0;
  std::vector<int> points_cm;  // x0, y0, x1, y1, ...: map-frame point minus the robot position, cm
};

struct ReportData {
  std::string error_kind;  // "relations" | "ate" | "" (no ground truth)
  std::vector<ReportRun> runs;
  // The run all runs are drawn on and aligned onto, and whose poses place the replay's scans: the
  // one with the smallest mean error when there is ground truth, else the first.
  std::size_t base = 0;
  std::vector<ReplayScan> replay;
  std::size_t log_scans = 0;  // scans in the log (the replay holds a subset)
};

struct ReportInputs {
  std::vector<std::string> run_dirs;
  std::string relations;   // or
  std::string reference;
  double stamp_tolerance = 0.001;
  std::string log;         // "" for no replay
  LogReaderOptions log_options;
  std::size_t max_replay_scans = 2000;
  std::size_t max_replay_points = 120;  // per scan
};

/// Reads everything; throws Error / ParseError naming the file at fault.
ReportData collect_report(const ReportInputs& inputs);

/// The blob, compact JSON; "</" is written "<\/" so that it can sit in a <script> element.
std::string report_json(const ReportData& data);

struct WrittenReport {
  std::string path;  // OUT_DIR/index.html
  std::size_t bytes = 0;
};

/// The page (the template report/report.html, embedded at build time as report_html.hpp, with the
/// blob in place of its placeholder), written atomically to out_dir/index.html.
WrittenReport write_report(const ReportData& data, const std::string& out_dir);

}  // namespace slam2d::cli
