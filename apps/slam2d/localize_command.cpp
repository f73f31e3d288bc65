// SPDX-License-Identifier: BSD-3-Clause
// slam2d localize LOG --map MAP.yaml --method markov|ekf|mcl|hybrid: localization in a known map
// (src/slam2d/localization, docs/methods/localization.md), one trajectory line per front-laser
// scan, and a summary with the convergence and recovery times and the cost per update.

#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <variant>
#include <vector>

#include "commands.hpp"
#include "json.hpp"
#include "odometry_report.hpp"
#include "progress.hpp"
#include "run_mcap_output.hpp"
#include "run_stats.hpp"
#include "sensor_options.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/hybrid.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/localization/session.hpp"
#include "slam2d/methods/method_presets.hpp"

namespace slam2d::cli {
namespace {

struct LocalizeOptions {
  std::string log;
  std::string map;
  std::string method = "mcl";
  std::string initial;  // x,y,theta (m, m, rad), map frame
  std::string initial_sigma = "0.3,0.3,0.2";
  bool global = false;
  std::string config;  // a method preset (configs/<method>.yaml); empty: the defaults
  std::optional<std::size_t> particles;  // overrides of the config when set
  std::optional<std::uint64_t> seed;
  std::optional<double> kidnap_at;
  std::string kidnap_by = "5,0,90";
  std::optional<std::string> sensor;
  LogReaderOptions input;  // CARMEN geometry overrides, bag topics and frames (sensor_options.hpp)
  std::string out;
  std::string trajectory_format = "text";  // text | tum
  std::string mcap;                        // when set: the run for Foxglove (io/run_mcap.hpp)
  bool json = false;
  bool quiet = false;
};

std::vector<double> parse_triple(const std::string& text, const std::string& option) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      std::size_t used = 0;
      values.push_back(std::stod(item, &used));
      check(used == item.size(), "");
    } catch (const std::exception&) {
      throw Error(fmt::format("localize: {} expects three numbers a,b,c, got '{}'", option, text));
    }
  }
  check(values.size() == 3 && std::isfinite(values[0]) && std::isfinite(values[1]) && std::isfinite(values[2]),
        fmt::format("localize: {} expects three finite numbers a,b,c, got '{}'", option, text));
  return values;
}

// The localizer of --method with its config (defaults, --config's preset, then the flags);
// `settings` gets what the summary reports of that config.
std::unique_ptr<Localizer> make_localizer(const LocalizeOptions& options, const LocalizationMap& map, JsonObject& settings) {
  const bool has_initial = !options.initial.empty();
  check(has_initial != options.global, "localize: give exactly one of --initial x,y,theta and --global");
  check(!(options.method == "ekf" && options.global),
        "localize: the EKF has no global mode (it tracks a unimodal Gaussian): give --initial, or use mcl, markov or hybrid");
  SE2 initial;
  Covariance3 covariance = Covariance3::Identity();
  if (has_initial) {
    const std::vector<double> pose = parse_triple(options.initial, "--initial");
    const std::vector<double> sigma = parse_triple(options.initial_sigma, "--initial-sigma");
    check(sigma[0] > 0.0 && sigma[1] > 0.0 && sigma[2] > 0.0, "localize: --initial-sigma must be positive");
    initial = SE2(pose[0], pose[1], pose[2]);
    covariance = covariance_from_sigmas(sigma[0], sigma[1], sigma[2]);
  }
  if (options.method == "mcl") {
    MclConfig config = read_method_preset(options.config, options.method, MclConfig{});
    if (options.particles) {
      check(*options.particles >= 10, "localize: --particles must be at least 10");
      config.max_particles = *options.particles;
      config.min_particles = std::min<std::size_t>(config.min_particles, *options.particles);
    }
    if (options.seed) config.seed = *options.seed;
    if (options.sensor) config.sensor = *options.sensor == "beam" ? SensorModelKind::kBeam : SensorModelKind::kLikelihoodField;
    settings.add("particles", config.max_particles).add("sensor", config.sensor == SensorModelKind::kBeam ? "beam" : "likelihood-field");
    auto mcl = std::make_unique<MonteCarloLocalization>(map, config);
    if (has_initial) mcl->initialize(initial, covariance);
    else mcl->initialize_global();
    return mcl;
  }
  check(!options.sensor && !options.particles, "localize: --sensor and --particles apply to --method mcl only");
  if (options.method == "ekf") {
    auto ekf = std::make_unique<EkfLocalization>(map, read_method_preset(options.config, options.method, EkfConfig{}));
    ekf->initialize(initial, covariance);
    return ekf;
  }
  if (options.method == "markov") {
    auto markov = std::make_unique<MarkovGridLocalization>(map, read_method_preset(options.config, options.method, MarkovGridConfig{}));
    if (has_initial) markov->initialize(initial, covariance);
    else markov->initialize_global();
    return markov;
  }
  auto hybrid = std::make_unique<HybridLocalization>(map, read_method_preset(options.config, options.method, HybridConfig{}));
  if (has_initial) hybrid->initialize(initial, covariance);
  else hybrid->initialize_global();
  return hybrid;
}

void run_localize(const LocalizeOptions& options) {
  const RunClock clock;
  const OccupancyMap occupancy = read_map(options.map);
  const LocalizationMap map(occupancy);
  JsonObject settings;
  std::unique_ptr<Localizer> localizer = make_localizer(options, map, settings);
  std::optional<Kidnap> kidnap;
  if (options.kidnap_at) {
    const std::vector<double> by = parse_triple(options.kidnap_by, "--kidnap-by");
    kidnap = Kidnap{.at = *options.kidnap_at, .by = SE2(by[0], by[1], deg_to_rad(by[2]))};
  }
  LocalizationSession session(*localizer, kidnap, OdometryGuardConfig{}, &map);
  LogReader reader(options.log, options.input);
  Progress progress("localize", options.quiet);
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type == "RLASER") continue;
    if (!laser->has_poses) {
      throw ParseError(reader.path(), laser->line, laser->type + " carries no odometry pose; localization needs odometry");
    }
    session.add(laser->odom_pose, laser->scan);
    if (session.summary().scans % 256 == 0) {
      progress.update(reader.progress(), fmt::format("{} scans, localized: {}", session.summary().scans,
                                                     session.localized().back() ? "yes" : "no"));
    }
  }
  progress.finish();
  print_reader_warnings(reader);
  const LocalizationRunSummary& run = session.summary();
  check(run.scans > 0, reader.path() + ": no front-laser scans in the log");
  const std::filesystem::path out(options.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  write_trajectory(options.out, session.trajectory(), trajectory_format_from_name(options.trajectory_format));
  if (!options.mcap.empty()) write_run_mcap(options.mcap, options.log, options.input, true, occupancy, session.trajectory());

  const double cpu = clock.cpu_seconds();
  JsonObject summary;
  summary.add("method", options.method).add("log", options.log).add("map", options.map);
  if (!options.config.empty()) summary.add("config", options.config);
  summary.merge(settings);
  summary.add("odometry_steps_reversed", reader.stats().odometry_steps_reversed);
  summary.merge(odometry_report(session.odometry_stats()));
  std::vector<std::string> warnings = reader_warnings(reader);
  if (const auto warning = odometry_warning(session.odometry_stats())) warnings.push_back(*warning);
  summary.add("global", options.global).add("scans", run.scans).add("sensor_updates", run.sensor_updates);
  summary.add("cpu_s", cpu).add("localizer_cpu_s", run.localizer_cpu_s);
  summary.add("us_per_update", 1e6 * run.localizer_cpu_s / static_cast<double>(std::max<std::size_t>(run.sensor_updates, 1)));
  summary.add("converged_at_s", run.converged_at_s);
  summary.add("localized_fraction", static_cast<double>(run.localized_scans) / static_cast<double>(run.scans));
  summary.add("lost_events", run.lost_events);
  summary.add("kidnapped_at_s", run.kidnapped_at_s).add("recovered_after_s", run.recovered_after_s);
  summary.add("data_duration_s", run.data_duration_s);
  summary.add("realtime_factor", cpu > 0.0 ? std::optional<double>(run.data_duration_s / cpu) : std::nullopt);
  summary.add("peak_rss_mb", peak_rss_mb()).add("trajectory", options.out);
  summary.add("warnings", warnings);
  std::fputs(options.json ? summary.dump().c_str() : summary.text().c_str(), stdout);
}

}  // namespace

void add_localize_command(CLI::App& app) {
  auto options = std::make_shared<LocalizeOptions>();
  CLI::App* command = app.add_subcommand("localize", "Localization in a known map: Markov grid, EKF, Monte Carlo, hybrid");
  command->add_option("log", options->log, "CARMEN log (plain or .gz), ROS 1 bag, MCAP file or rosbag2 folder, with odometry")->required();
  command->add_option("--map", options->map, "Map YAML (ROS map_server format, e.g. from slam2d map)")->required();
  command->add_option("--method", options->method, "Localization method")
      ->check(CLI::IsMember({"markov", "ekf", "mcl", "hybrid"}))
      ->capture_default_str();
  command->add_option("--initial", options->initial, "Initial pose x,y,theta (m, m, rad) in the map frame");
  command->add_option("--initial-sigma", options->initial_sigma, "Standard deviations of the initial pose (m, m, rad)")
      ->capture_default_str();
  command->add_flag("--global", options->global, "Global localization from a uniform prior (not ekf)");
  command->add_option("--config", options->config,
                      "A method preset (configs/<method>.yaml; `slam2d config dump METHOD` prints the defaults); the flags below override it")
      ->check(CLI::ExistingFile);
  command->add_option("--particles", options->particles, "mcl: maximum particle count (default 5000; KLD-sampling adapts below it)");
  command->add_option("--sensor", options->sensor, "mcl: sensor model (default likelihood-field)")
      ->check(CLI::IsMember({"likelihood-field", "beam"}));
  command->add_option("--seed", options->seed, "mcl: random seed (default 1)");
  command->add_option("--kidnap-at", options->kidnap_at, "s after the first scan: corrupt the odometry once (kidnap test)");
  command->add_option("--kidnap-by", options->kidnap_by, "The kidnap's extra motion dx,dy,dtheta (m, m, deg; robot frame)")
      ->capture_default_str();
  add_sensor_options(command, options->input);
  command->add_option("--out", options->out, "Trajectory file (one line per scan: stamp x y theta)")->required();
  command->add_option("--mcap", options->mcap,
                      "Also write the run for Foxglove: map, path, poses, scans (and in the map frame), tf (MCAP, ROS 2 types)");
  command->add_option("--format", options->trajectory_format, "The trajectory as slam2d text (t x y theta) or tum (evo's format)")
      ->check(CLI::IsMember({"text", "tum"}))
      ->capture_default_str();
  command->add_flag("--json", options->json, "Print the summary as JSON");
  command->add_flag("--quiet", options->quiet, "No progress line");
  command->callback([options] { run_localize(*options); });
}

}  // namespace slam2d::cli
