// SPDX-License-Identifier: BSD-3-Clause
// `slam2d report`: the HTML page over a graph SLAM run and an odometry run of a simulated log,
// with the simulator's truth as the reference and the log's scan replay. The data blob is checked
// against `slam2d eval`; the page is opened in headless Chromium (skipped when /usr/bin/chromium
// is absent), which must render every canvas without a JavaScript error.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "slam2d/io/map_io.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::json_number;
using test::run_command;
using test::slam2d;
using test::TempDir;

constexpr const char* kChromium = "/usr/bin/chromium";

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The text of the element `<TAG ... id="ID" ...>TEXT</TAG>` (no nested element of that tag).
std::string element_text(const std::string& html, const std::string& tag, const std::string& id) {
  const std::size_t open = html.find(" id=\"" + id + "\"");
  if (open == std::string::npos) return "";
  const std::size_t start = html.find('>', open) + 1;
  return html.substr(start, html.find("</" + tag + ">", start) - start);
}

/// `&lt;` and friends back to characters (the DOM dump escapes a <pre>'s text).
std::string unescape_html(std::string text) {
  static const std::array<std::pair<std::string, std::string>, 4> kEntities{
      {{"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&amp;", "&"}}};
  for (const auto& [entity, character] : kEntities) {
    for (std::size_t at = text.find(entity); at != std::string::npos; at = text.find(entity, at + 1)) {
      text.replace(at, entity.size(), character);
    }
  }
  return text;
}

class ReportCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim_ = new test::SimulatedLog(120, 5);  // long enough for graph SLAM to close loops
    out_ = new TempDir();
    for (const char* method : {"graph", "odometry"}) {
      const CommandResult mapped = run_command(slam2d("map --quiet " + sim_->log() + " --method " + method + " --out " +
                                                      run_dir(method)));
      ASSERT_EQ(mapped.exit_code, 0) << mapped.errors;
    }
    report_ = new CommandResult(run_command(slam2d("report " + run_dir("graph") + " " + run_dir("odometry") +
                                                   " --reference " + sim_->truth() + " --log " + sim_->log() +
                                                   " --out " + report_dir() + " --json")));
  }
  static void TearDownTestSuite() {
    delete report_;
    delete out_;
    delete sim_;
  }
  static std::string run_dir(const std::string& method) { return out_->file(method); }
  static std::string report_dir() { return out_->file("report"); }
  static std::string index_html() { return report_dir() + "/index.html"; }
  /// The JSON blob of the page.
  static YAML::Node report_data() {
    return YAML::Load(element_text(read_text(index_html()), "script", "report-data"));
  }

  static test::SimulatedLog* sim_;
  static TempDir* out_;
  static CommandResult* report_;
};

test::SimulatedLog* ReportCli::sim_ = nullptr;
TempDir* ReportCli::out_ = nullptr;
CommandResult* ReportCli::report_ = nullptr;

TEST_F(ReportCli, WritesThePageAndAJsonSummary) {
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  ASSERT_TRUE(std::filesystem::exists(index_html()));
  const YAML::Node summary = YAML::Load(report_->output);
  EXPECT_EQ(summary["path"].as<std::string>(), index_html());
  EXPECT_EQ(summary["bytes"].as<std::size_t>(), std::filesystem::file_size(index_html()));
  ASSERT_EQ(summary["runs"].size(), 2u);
  EXPECT_EQ(summary["runs"][0].as<std::string>(), "graph");
  EXPECT_GT(summary["replay_scans"].as<int>(), 10);
}

TEST_F(ReportCli, EmbedsBothRunsWithMapsTrajectoriesAndLoopClosures) {
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  const YAML::Node data = report_data();
  ASSERT_TRUE(data.IsMap());
  EXPECT_EQ(data["error_kind"].as<std::string>(), "ate");
  ASSERT_EQ(data["runs"].size(), 2u);
  const YAML::Node graph = data["runs"][0];
  const YAML::Node odometry = data["runs"][1];
  EXPECT_EQ(graph["summary"]["method"].as<std::string>(), "graph");
  EXPECT_EQ(graph["trajectory"]["x"].size(), test::count_data_lines(run_dir("graph") + "/trajectory.txt"));
  EXPECT_EQ(graph["map"]["png"].as<std::string>().rfind("data:image/png;base64,", 0), 0u);
  EXPECT_GT(graph["loop_closures"].size(), 0u) << "the 120 s office route closes loops";
  EXPECT_EQ(odometry["loop_closures"].size(), 0u);
  EXPECT_GT(graph["cpu_s"].as<double>(), 0.0);
}

TEST_F(ReportCli, ErrorsMatchSlam2dEvalsAte) {
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  const YAML::Node data = report_data();
  for (std::size_t i = 0; i < 2; ++i) {
    const YAML::Node run = data["runs"][i];
    const std::string trajectory = run["dir"].as<std::string>() + "/trajectory.txt";
    const CommandResult eval = run_command(slam2d("eval " + trajectory + " --reference " + sim_->truth() + " --json"));
    ASSERT_EQ(eval.exit_code, 0) << eval.errors;
    const YAML::Node stats = run["error_stats"];
    EXPECT_EQ(stats["count"].as<double>(), *json_number(eval.output, "matched"));
    EXPECT_NEAR(stats["mean"].as<double>(), *json_number(eval.output, "ate_mean"), 1e-4);
    EXPECT_NEAR(stats["median"].as<double>(), *json_number(eval.output, "ate_median"), 1e-4);
    EXPECT_NEAR(stats["max"].as<double>(), *json_number(eval.output, "ate_max"), 1e-4);
    EXPECT_NEAR(stats["rmse"].as<double>(), *json_number(eval.output, "ate_rmse"), 1e-4);
    EXPECT_EQ(run["errors"]["e"].size(), stats["count"].as<std::size_t>());
  }
  EXPECT_LT(data["runs"][0]["error_stats"]["rmse"].as<double>(), data["runs"][1]["error_stats"]["rmse"].as<double>())
      << "graph SLAM beats odometry";
}

// All runs are drawn on, and aligned onto, the run with the smallest mean error, wherever it is in
// the list; without ground truth, the first run.
TEST_F(ReportCli, DrawsEveryRunOnTheMostAccurateRunsMap) {
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  const std::string runs = run_dir("odometry") + " " + run_dir("graph");
  ASSERT_EQ(run_command(slam2d("report --quiet " + runs + " --reference " + sim_->truth() + " --out " + out_->file("swapped")))
                .exit_code,
            0);
  const YAML::Node data = YAML::Load(element_text(read_text(out_->file("swapped") + "/index.html"), "script", "report-data"));
  ASSERT_EQ(data["base"].as<std::size_t>(), 1u);
  const YAML::Node graph = data["runs"][1];
  const YAML::Node odometry = data["runs"][0];
  EXPECT_LT(graph["error_stats"]["mean"].as<double>(), odometry["error_stats"]["mean"].as<double>());
  // The base run aligned onto itself stays where it is; the odometry comes onto it (within its drift).
  double base_offset = 0.0;
  double odometry_offset = 0.0;
  const std::size_t n = graph["trajectory"]["x"].size();
  ASSERT_EQ(odometry["overlay"]["x"].size(), n);
  for (std::size_t i = 0; i < n; ++i) {
    const double gx = graph["trajectory"]["x"][i].as<double>(), gy = graph["trajectory"]["y"][i].as<double>();
    base_offset = std::max(base_offset, std::hypot(graph["overlay"]["x"][i].as<double>() - gx, graph["overlay"]["y"][i].as<double>() - gy));
    odometry_offset += std::hypot(odometry["overlay"]["x"][i].as<double>() - gx, odometry["overlay"]["y"][i].as<double>() - gy) / n;
  }
  EXPECT_LT(base_offset, 0.011);  // positions rounded to cm
  EXPECT_LT(odometry_offset, 1.0);
  ASSERT_EQ(run_command(slam2d("report --quiet " + runs + " --out " + out_->file("no-truth"))).exit_code, 0);
  const YAML::Node plain = YAML::Load(element_text(read_text(out_->file("no-truth") + "/index.html"), "script", "report-data"));
  EXPECT_EQ(plain["base"].as<std::size_t>(), 0u);
}

TEST_F(ReportCli, ReplayScansLieOnTheFirstRunsMap) {
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  const YAML::Node data = report_data();
  const YAML::Node scans = data["replay"]["scans"];
  ASSERT_GT(scans.size(), 10u);
  EXPECT_LE(scans.size(), 2000u);
  EXPECT_GE(data["replay"]["log_scans"].as<std::size_t>(), scans.size());
  const YAML::Node map = data["runs"][0]["map"];
  const double x0 = map["origin"][0].as<double>(), y0 = map["origin"][1].as<double>();
  const double res = map["resolution"].as<double>();
  const double x1 = x0 + map["width"].as<double>() * res, y1 = y0 + map["height"].as<double>() * res;
  std::size_t points = 0, inside = 0;
  for (const YAML::Node& scan : scans) {
    const YAML::Node offsets = scan[4];
    for (std::size_t k = 0; k + 1 < offsets.size(); k += 2, ++points) {
      const double x = scan[1].as<double>() + offsets[k].as<int>() / 100.0;
      const double y = scan[2].as<double>() + offsets[k + 1].as<int>() / 100.0;
      if (x >= x0 && x <= x1 && y >= y0 && y <= y1) ++inside;
    }
  }
  ASSERT_GT(points, 1000u);
  EXPECT_GT(static_cast<double>(inside), 0.99 * static_cast<double>(points)) << "scan points fall on the map";
}

TEST_F(ReportCli, PageIsSelfContained) {
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  const std::string html = read_text(index_html());
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*["']?(//|[a-z]+:))")));
  EXPECT_EQ(html.find("@REPORT_DATA@"), std::string::npos) << "the placeholder is replaced";
  EXPECT_NE(html.find("<pre id=\"render-check\">"), std::string::npos);
}

TEST_F(ReportCli, RelationsGiveOneErrorPerRelation) {
  // Relations from the truth: each pose to the one 10 poses later.
  const TempDir dir;
  const std::string relations = dir.file("truth.relations");
  {
    std::ifstream truth(sim_->truth());
    std::vector<std::array<double, 4>> poses;
    std::array<double, 4> p{};
    std::string line;
    while (std::getline(truth, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream(line) >> p[0] >> p[1] >> p[2] >> p[3];
      poses.push_back(p);
    }
    std::ofstream out(relations);
    for (std::size_t i = 0; i + 10 < poses.size(); i += 10) {
      const auto& a = poses[i];
      const auto& b = poses[i + 10];
      const double c = std::cos(a[3]), s = std::sin(a[3]), dx = b[1] - a[1], dy = b[2] - a[2];
      out << a[0] << " " << b[0] << " " << c * dx + s * dy << " " << -s * dx + c * dy << " 0 0 0 " << b[3] - a[3] << "\n";
    }
  }
  const CommandResult report = run_command(slam2d("report " + run_dir("graph") + " --relations " + relations +
                                                  " --out " + dir.file("report") + " --quiet"));
  ASSERT_EQ(report.exit_code, 0) << report.errors;
  EXPECT_TRUE(report.output.empty()) << "--quiet";
  const YAML::Node data = YAML::Load(element_text(read_text(dir.file("report/index.html")), "script", "report-data"));
  EXPECT_EQ(data["error_kind"].as<std::string>(), "relations");
  const CommandResult eval = run_command(slam2d("eval " + run_dir("graph") + "/trajectory.txt --relations " + relations + " --json"));
  ASSERT_EQ(eval.exit_code, 0) << eval.errors;
  EXPECT_EQ(data["runs"][0]["error_stats"]["count"].as<double>(), *json_number(eval.output, "relations"));
  EXPECT_NEAR(data["runs"][0]["error_stats"]["mean"].as<double>(), *json_number(eval.output, "trans_mean"), 1e-4);
  EXPECT_EQ(data["replay"]["scans"].size(), 0u) << "no --log, no replay";
}

TEST_F(ReportCli, BadInputFailsNamingTheFile) {
  const TempDir dir;
  const std::string out = " --out " + dir.file("report");
  const std::string missing_run = dir.file("no-such-run");
  CommandResult result = run_command(slam2d("report " + missing_run + out));
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.errors.find(missing_run), std::string::npos) << result.errors;

  std::filesystem::create_directories(dir.file("empty-run"));
  result = run_command(slam2d("report " + dir.file("empty-run") + out));
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.errors.find(dir.file("empty-run") + "/trajectory.txt"), std::string::npos) << result.errors;

  const std::string relations = dir.file("bad.relations");
  std::ofstream(relations) << "1.0 2.0 not a relation\n";
  result = run_command(slam2d("report " + run_dir("graph") + " --relations " + relations + out));
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.errors.find(relations + ":1:"), std::string::npos) << result.errors;
  EXPECT_FALSE(std::filesystem::exists(dir.file("report/index.html"))) << "nothing written on failure";
}

// ---- headless Chromium ---------------------------------------------------------------------

std::string chromium(const std::string& arguments) {
  return std::string(kChromium) +
         " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking"
         " --disable-component-update --disable-sync --user-data-dir=$(mktemp -d) --virtual-time-budget=10000 " +
         arguments + " 2>/dev/null";
}

TEST_F(ReportCli, ChromiumRendersEveryCanvasWithoutErrors) {
  if (!std::filesystem::exists(kChromium)) GTEST_SKIP() << "headless browser test: /usr/bin/chromium is not installed";
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  const CommandResult dom = run_command(chromium("--dump-dom file://" + index_html()));
  ASSERT_EQ(dom.exit_code, 0) << dom.errors;
  EXPECT_NE(dom.output.find("data-status=\"rendered\""), std::string::npos) << dom.output.substr(0, 2000);
  EXPECT_EQ(unescape_html(element_text(dom.output, "pre", "errors")), "") << "JavaScript errors";
  const YAML::Node check = YAML::Load(unescape_html(element_text(dom.output, "pre", "render-check")));
  ASSERT_TRUE(check.IsMap()) << dom.output.substr(0, 2000);
  EXPECT_EQ(check["runs"].as<int>(), 2);
  EXPECT_EQ(check["maps"].as<int>(), 4) << "the overlay, the replay and one per run";
  EXPECT_EQ(check["plots"].as<int>(), 3) << "the CDF and one error-over-time per run";
  EXPECT_EQ(check["worst_rows"].as<int>(), 20);
  EXPECT_EQ(check["summary_rows"].as<int>(), 2);
  EXPECT_GT(check["replay_scans"].as<int>(), 10);
  std::size_t map_canvases = 0, plot_canvases = 0;
  for (const auto& entry : check["canvases"]) {
    const std::string id = entry.first.as<std::string>();
    const std::string kind = entry.second["kind"].as<std::string>();
    (kind == "map" ? map_canvases : plot_canvases) += 1;
    EXPECT_GT(entry.second["ink"].as<int>(), kind == "map" ? 5000 : 500) << id << " is (nearly) blank";
  }
  EXPECT_EQ(map_canvases, 4u);
  EXPECT_EQ(plot_canvases, 3u);
}

TEST_F(ReportCli, ChromiumScreenshotIsNotBlank) {
  if (!std::filesystem::exists(kChromium)) GTEST_SKIP() << "headless browser test: /usr/bin/chromium is not installed";
  ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  const TempDir dir;
  const std::string shot = dir.file("shot.png");
  const CommandResult result = run_command(chromium("--screenshot=" + shot + " --window-size=1400,2000 file://" + index_html()));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const RgbImage image = read_png_rgb(shot);
  EXPECT_EQ(image.width, 1400);
  std::set<std::uint32_t> colours;
  std::size_t white = 0;
  for (std::size_t i = 0; i + 2 < image.rgb.size(); i += 3) {
    colours.insert(image.rgb[i] << 16 | image.rgb[i + 1] << 8 | image.rgb[i + 2]);
    white += image.rgb[i] == 255 && image.rgb[i + 1] == 255 && image.rgb[i + 2] == 255;
  }
  EXPECT_GT(colours.size(), 20u) << "maps, trajectories and error colours";
  EXPECT_LT(static_cast<double>(white), 0.95 * static_cast<double>(image.rgb.size() / 3));
}

}  // namespace
}  // namespace slam2d
