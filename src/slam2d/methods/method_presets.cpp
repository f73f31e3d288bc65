// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/methods/method_presets.hpp"

#include <algorithm>
#include <functional>
#include <utility>

#include "slam2d/core/error.hpp"
#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/hybrid.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/methods/matcher_registry.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"

namespace slam2d {
namespace {

struct MethodEntry {
  std::string name;
  std::function<std::vector<FieldRow>(const std::string& preset_path)> fields;
};

template <typename Config>
MethodEntry method(std::string name, Config defaults) {
  return {name, [name, defaults](const std::string& path) {
            return field_rows(read_method_preset(path, name, defaults));
          }};
}

const std::vector<MethodEntry>& methods() {
  static const std::vector<MethodEntry> table{
      method("hector", HectorSlamConfig{}),   method("graph", GraphSlamConfig{}),
      method("rbpf", RbpfConfig{}),           method("mcl", MclConfig{}),
      method("ekf", EkfConfig{}),             method("markov", MarkovGridConfig{}),
      method("hybrid", HybridConfig{}),
  };
  return table;
}

const MethodEntry* find_method(const std::string& name) {
  for (const MethodEntry& entry : methods()) {
    if (entry.name == name) return &entry;
  }
  return nullptr;
}

[[noreturn]] void unknown_name(const std::string& name) {
  std::string list;
  for (const std::string& known : configurable_names()) list += (list.empty() ? "" : ", ") + known;
  throw Error("unknown method or matcher '" + name + "' (known: " + list + ")");
}

bool is_matcher(const std::string& name) {
  const auto& names = matcher_names();
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

const std::vector<std::string>& method_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const MethodEntry& entry : methods()) out.push_back(entry.name);
    return out;
  }();
  return names;
}

std::vector<FieldRow> method_fields(const std::string& name, const std::string& preset_path) {
  if (const MethodEntry* entry = find_method(name)) return entry->fields(preset_path);
  std::string list;
  for (const std::string& known : method_names()) list += (list.empty() ? "" : ", ") + known;
  throw Error("unknown method '" + name + "' (known: " + list + ")");
}

ConfigNode load_method_preset(const std::string& path, const std::string& method) {
  const ConfigNode root = ConfigNode::load(path);
  if (!root.is_map()) throw root.error("a method preset is a map of settings");
  std::string named;
  if (!root.read("method", named)) throw root.error("a method preset needs a 'method: NAME' key");
  if (named != method) {
    throw root.at("method").error("this preset is for method '" + named + "', not '" + method + "'");
  }
  return root;
}

std::string default_preset(const std::string& name) {
  if (find_method(name) != nullptr) return "method: " + name + "\n" + config_yaml(method_fields(name));
  if (is_matcher(name)) return "matcher: " + name + "\n" + config_yaml(matcher_fields(name));
  unknown_name(name);
}

std::string config_table(const std::string& name) {
  if (find_method(name) != nullptr) return config_markdown(method_fields(name));
  if (is_matcher(name)) return config_markdown(matcher_fields(name));
  unknown_name(name);
}

std::vector<std::string> configurable_names() {
  std::vector<std::string> names = method_names();
  for (const std::string& name : matcher_names()) names.push_back(name);
  return names;
}

std::string configuration_docs() {
  std::string page =
      "# Configuration\n\n"
      "Every setting of every method and matcher, with its default, unit, allowed range and meaning.\n"
      "Generated from the config structs' field tables (`src/slam2d/core/config_fields.hpp`) by\n"
      "`slam2d config docs > docs/configuration.md`; a test fails when this page and the tables differ.\n\n"
      "A preset is a YAML file with `method: NAME` (for `slam2d map --config` and `slam2d localize --config`)\n"
      "or `matcher: NAME` (for `--matcher`) and any of the fields below under the same names, sections as\n"
      "nested maps. `slam2d config dump NAME` prints one with every default; unknown keys, wrong types and\n"
      "values out of range are refused with the file and line. Flags given on the command line override\n"
      "the preset. Units: m, rad, s; 1 is dimensionless. A list (the pipeline's filters) holds items\n"
      "`{kind: NAME, ...}` with that kind's fields; given, it replaces the whole default list.\n";
  for (const std::string& name : configurable_names()) page += "\n## " + name + "\n\n" + config_table(name);
  return page;
}

}  // namespace slam2d
