// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Every mapping and localization method by name, with its configuration from the defaults or from
// a YAML preset (configs/<method>.yaml): what `slam2d map --config` and `slam2d localize --config`
// read, and what `slam2d config dump|table` print.
//
// A method preset holds `method: <name>` and the fields of that method's config struct under the
// same names (sections as nested maps), read by the struct's field table (core/config_fields.hpp);
// unknown keys, wrong types and values out of range are ParseErrors naming the file and line.

#include <string>
#include <vector>

#include "slam2d/io/config_file.hpp"
#include "slam2d/io/config_text.hpp"

namespace slam2d {

/// The methods with a preset: hector, graph, rbpf (map) and mcl, ekf, markov, hybrid (localize).
const std::vector<std::string>& method_names();

/// The fields of method `name`'s config: the library defaults, or with the preset at `preset_path`
/// read over them (validated). Throws Error for an unknown name, ParseError for a bad preset.
std::vector<FieldRow> method_fields(const std::string& name, const std::string& preset_path = "");

/// The root of the preset at `path`, checked to be for `method`.
ConfigNode load_method_preset(const std::string& path, const std::string& method);

/// `config` with the fields of the preset at `path` (for `method`) read over it, then validated;
/// an invalid combination is a ParseError naming the file. An empty path (no --config) gives
/// `config` as it is.
template <typename Config>
Config read_method_preset(const std::string& path, const std::string& method, Config config) {
  if (path.empty()) return config;
  read_valid_config(load_method_preset(path, method), config);
  return config;
}

/// A method's or a matcher's defaults as a preset file: `method: NAME` (or `matcher: NAME`) and
/// every field, commented with its unit, range and meaning. Reads back to the defaults.
std::string default_preset(const std::string& name);
/// The Markdown table of a method's or a matcher's fields (field, default, unit, range, meaning).
std::string config_table(const std::string& name);
/// Every method and matcher with a field table, methods first.
std::vector<std::string> configurable_names();
/// docs/configuration.md: every method's and matcher's table (`slam2d config docs`).
std::string configuration_docs();

}  // namespace slam2d
