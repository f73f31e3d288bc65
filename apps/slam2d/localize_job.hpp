// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What `slam2d localize` is given, and the localizer it makes of it: the command's options and
// make_localizer, shared with the Python module (slam2d.Localizer).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "json.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/localization/localization_map.hpp"
#include "slam2d/localization/localizer.hpp"

namespace slam2d::cli {

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
  std::string odometry_time_offset = "auto";  // auto | off | seconds (sensor_options.hpp)
  std::string out;
  std::string trajectory_format = "text";  // text | tum
  std::string mcap;                        // when set: the run for Foxglove (io/run_mcap.hpp)
  std::string png;                         // when set: the map with the run drawn on it (lost segments, end uncertainty)
  bool odometry_smoothing = true;          // the written poses smoothed with the odometry (localize_command.cpp)
  bool json = false;
  bool quiet = false;
};

/// "a,b,c" as three finite numbers; Error naming `option` otherwise.
std::vector<double> parse_triple(const std::string& text, const std::string& option);

/// The localizer of options.method with its config (defaults, options.config's preset, then the
/// overrides), initialized at options.initial or globally; `settings` gets what the summary
/// reports of that config.
std::unique_ptr<Localizer> make_localizer(const LocalizeOptions& options, const LocalizationMap& map, JsonObject& settings);

}  // namespace slam2d::cli
