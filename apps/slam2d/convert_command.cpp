// SPDX-License-Identifier: BSD-3-Clause
// slam2d convert IN OUT: a log in another format (io/log_writer.hpp): CARMEN, ROS 1 bag, MCAP or
// rosbag2 folder in, any of them out, written atomically.

#include <fmt/core.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.hpp"
#include "json.hpp"
#include "progress.hpp"
#include "sensor_options.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/log_writer.hpp"

namespace slam2d::cli {

namespace {

struct ConvertOptions {
  std::string in;
  std::string out;
  std::string to;  // empty: from OUT's name
  LogReaderOptions input;
  bool json = false;
  bool quiet = false;
};

void run_convert(const ConvertOptions& options) {
  const LogFormat to = options.to.empty() ? log_format_for_output(options.out) : parse_log_format(options.to);
  Progress progress("convert", options.quiet);
  LogReader reader(options.in, options.input);
  const std::vector<SensorMessage> messages =
      read_all(reader, [&](double fraction, std::size_t n) { progress.update(fraction, fmt::format("{} messages read", n)); });
  progress.update(-1.0, "writing");
  const std::filesystem::path out(options.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  const std::string name = std::filesystem::path(options.in).filename().string();
  const LogWriteReport report =
      write_log(options.out, to, messages, {"slam2d convert of " + name + " (" + log_format_name(reader.format()) + ")"});
  progress.finish();
  const std::vector<std::string> warnings = reader_warnings(reader);
  if (!options.quiet) print_reader_warnings(reader);

  JsonObject summary;
  summary.add("in", options.in).add("in_format", log_format_name(reader.format()));
  summary.add("out", options.out).add("out_format", log_format_name(to));
  summary.add("messages", messages.size()).add("scans", report.scans).add("odometry", report.odometry);
  summary.add("imu", report.imu).add("true_poses", report.true_poses).add("not_written", report.not_written);
  if (options.json) {
    std::fputs(summary.dump().c_str(), stdout);
  } else if (!options.quiet) {
    std::fputs(summary.text().c_str(), stdout);
    if (report.not_written > 0) {
      std::fprintf(stderr, "%s: warning: %zu messages the format has no place for were not written (%s)\n",
                   options.out.c_str(), report.not_written,
                   to == LogFormat::kCarmen ? "IMU readings" : "true poses");
    }
  }
}

}  // namespace

void add_convert_command(CLI::App& app) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* command = app.add_subcommand(
      "convert", "Convert a log between CARMEN, ROS 1 bag, MCAP and rosbag2 (docs/bags.md)");
  command->add_option("in", options->in, "Log to read: CARMEN (plain or .gz), ROS 1 .bag, .mcap or rosbag2 folder")
      ->required();
  command->add_option("out", options->out,
                      "Log to write; its name gives the format: .bag ROS 1, .mcap MCAP, no extension or a trailing / a "
                      "rosbag2 folder, else CARMEN (.gz: gzip)")
      ->required();
  command->add_option("--to", options->to, "Output format instead of OUT's name: carmen, ros1, mcap, rosbag2")
      ->check(CLI::IsMember({"carmen", "ros1", "mcap", "rosbag2"}));
  add_sensor_options(command, options->input);
  command->add_flag("--json", options->json, "Print a JSON summary");
  command->add_flag("--quiet", options->quiet, "No progress line; no summary unless --json");
  command->callback([options] { run_convert(*options); });
}

}  // namespace slam2d::cli
