// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/methods/matcher_registry.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <utility>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/correlative.hpp"
#include "slam2d/registration/ga_icp.hpp"
#include "slam2d/registration/icp.hpp"
#include "slam2d/registration/idc.hpp"
#include "slam2d/registration/pipeline.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "slam2d/registration/point_to_plane.hpp"
#include "slam2d/registration/tangent_search.hpp"
#include "slam2d/registration/trimmed_icp.hpp"
#include "slam2d/registration/weighted_icp.hpp"

namespace slam2d {
namespace {

// The cloud-to-cloud overload of a matcher that also has others (prebuilt tables or trees).
template <typename Config>
auto cloud_matcher(MatchResult (*match)(const PointCloud2&, const PointCloud2&, const SE2&, const Config&)) {
  return match;
}

// A matcher bound to a config read from `node` by its field table (validated now, so a bad
// preset fails at load).
template <typename Config, typename Match>
Matcher bind(const ConfigNode& node, Config config, Match match) {
  read_valid_config(node, config);
  return [config, match](const PointCloud2& target, const PointCloud2& source, const SE2& guess) {
    return match(target, source, guess, config);
  };
}

// One named matcher: how to make it from a preset, and its field table with the defaults.
struct Entry {
  std::string name;
  std::function<Matcher(const ConfigNode&)> make;
  std::function<std::vector<FieldRow>()> fields;
};

template <typename Config, typename Match>
Entry entry(std::string name, Config defaults, Match match) {
  return {std::move(name), [defaults, match](const ConfigNode& n) { return bind(n, defaults, match); },
          [defaults] { return field_rows(defaults); }};
}

const std::vector<Entry>& entries() {
  static const std::vector<Entry> table{
      entry("icp", IcpConfig{}, match_icp),
      entry("icp-accelerated", IcpConfig{.accelerated = true}, match_icp),
      entry("trimmed-icp", TrimmedIcpConfig{}, match_trimmed_icp),
      entry("pl-icp", PlIcpConfig{}, match_pl_icp),
      entry("point-to-plane", PointToPlaneConfig{}, cloud_matcher<PointToPlaneConfig>(match_point_to_plane)),
      entry("imrp", ImrpConfig{}, match_imrp),
      entry("idc", IdcConfig{}, match_idc),
      entry("tangent-search", TangentSearchConfig{}, match_tangent_search),
      entry("boolean-icp", WeightedIcpConfig{}, match_boolean_icp),
      entry("soft-icp", WeightedIcpConfig{.weighting = IcpWeighting::kSoft}, match_soft_icp),
      entry("ga-icp", GaIcpConfig{}, match_ga_icp),
      entry("correlative", CorrelativeConfig{}, cloud_matcher<CorrelativeConfig>(match_correlative)),
      entry("pipeline", PipelineConfig{}, match_pipeline),
  };
  return table;
}

const Entry& find_entry(const std::string& name) {
  for (const Entry& known : entries()) {
    if (known.name == name) return known;
  }
  std::string list;
  for (const std::string& known : matcher_names()) list += (list.empty() ? "" : ", ") + known;
  throw Error("unknown matcher '" + name + "' (known: " + list + ")");
}

}  // namespace

const std::vector<std::string>& matcher_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Entry& known : entries()) out.push_back(known.name);
    return out;
  }();
  return names;
}

Matcher make_matcher(const std::string& name) { return find_entry(name).make(ConfigNode()); }

Matcher make_matcher(const std::string& name, const ConfigNode& config) {
  const Entry& known = find_entry(name);
  std::string named = name;
  if (config.read("matcher", named) && named != name) {
    throw config.at("matcher").error("this preset is for matcher '" + named + "', not '" + name + "'");
  }
  return known.make(config);
}

std::vector<FieldRow> matcher_fields(const std::string& name) { return find_entry(name).fields(); }

Matcher load_matcher(const std::string& yaml_path) {
  const ConfigNode config = ConfigNode::load(yaml_path);
  if (config.has("method")) throw config.error("this is a method preset (for slam2d map|localize --config), not a matcher preset");
  if (!config.has("matcher")) throw config.error("a matcher preset needs a 'matcher: NAME' key");
  return make_matcher(config.at("matcher").as_string(), config);
}

Matcher matcher_from_argument(const std::string& name_or_path) {
  const auto ends_with = [&](const std::string& suffix) {
    return name_or_path.size() >= suffix.size() &&
           name_or_path.compare(name_or_path.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (ends_with(".yaml") || ends_with(".yml")) return load_matcher(name_or_path);
  return make_matcher(name_or_path);
}

}  // namespace slam2d
