#include "slam2d/methods/pipeline_config.hpp"

#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "slam2d/core/error.hpp"

namespace slam2d {
namespace {

// Runs a validation; its Error becomes a ParseError at `node` (the map of the offending values).
template <typename Check>
void validated(const ConfigNode& node, Check&& check) {
  try {
    check();
  } catch (const ParseError&) {
    throw;
  } catch (const Error& e) {
    throw node.error(e.what());
  }
}

void read_fields(const ConfigNode& node, RangeClipFilter& filter) {
  node.read("min", filter.min);
  node.read("max", filter.max);
}
void read_fields(const ConfigNode& node, VoxelGridFilter& filter) { node.read("size", filter.size); }
void read_fields(const ConfigNode& node, RandomSubsampleFilter& filter) {
  node.read("ratio", filter.ratio);
  node.read("seed", filter.seed);
}
void read_fields(const ConfigNode& node, NormalsFilter& filter) {
  node.read("neighbors", filter.neighbors);
  node.read("max_neighbor_distance", filter.max_neighbor_distance);
  node.read("min_neighbors", filter.min_neighbors);
  node.read("ordered", filter.ordered);
}
void read_fields(const ConfigNode& node, MaxDistanceFilter& filter) { node.read("distance", filter.distance); }
void read_fields(const ConfigNode& node, TrimmedFilter& filter) { node.read("ratio", filter.ratio); }
void read_fields(const ConfigNode& node, MedianFactorFilter& filter) {
  node.read("factor", filter.factor);
  node.read("quantile", filter.quantile);
}
void read_fields(const ConfigNode& node, NormalAngleFilter& filter) { node.read("max_angle", filter.max_angle); }

// One list item {kind: <name>, <field>: <value>, ...}: the kind picks the variant alternative
// (defaults), the other keys must be that alternative's fields.
template <typename Variant>
Variant read_filter(const ConfigNode& item, const std::vector<std::pair<std::string, Variant>>& kinds) {
  if (!item.is_map()) throw item.error("expected a filter {kind: ..., ...}");
  Variant filter = kinds.front().second;
  if (!item.read_enum("kind", filter, kinds)) throw item.error("a filter needs a 'kind'");
  std::visit([&](auto& alternative) { read_fields(item, alternative); }, filter);
  item.reject_unread_keys();
  validated(item, [&] { validate(filter); });
  return filter;
}

template <typename Variant>
void read_filters(const ConfigNode& node, const std::string& key, std::vector<Variant>& filters,
                  const std::vector<std::pair<std::string, Variant>>& kinds) {
  if (!node.has(key)) return;
  const ConfigNode list = node.at(key);
  filters.clear();
  if (list.is_null()) return;  // `key:` with no value: no filter
  for (const ConfigNode& item : list.items()) filters.push_back(read_filter(item, kinds));
}

const std::vector<std::pair<std::string, DataFilterConfig>>& data_filter_kinds() {
  static const std::vector<std::pair<std::string, DataFilterConfig>> kinds = {
      {"range_clip", RangeClipFilter{}}, {"voxel", VoxelGridFilter{}}, {"random", RandomSubsampleFilter{}},
      {"normals", NormalsFilter{}}};
  return kinds;
}

const std::vector<std::pair<std::string, OutlierFilterConfig>>& outlier_filter_kinds() {
  static const std::vector<std::pair<std::string, OutlierFilterConfig>> kinds = {
      {"max_distance", MaxDistanceFilter{}}, {"trimmed", TrimmedFilter{}}, {"median_factor", MedianFactorFilter{}},
      {"normal_angle", NormalAngleFilter{}}};
  return kinds;
}

void read_association(const ConfigNode& node, AssociationConfig& association) {
  if (!node.is_map()) throw node.error("expected a map {kind: kdtree | projective, max_distance: ..., window: ...}");
  node.read_enum("kind", association.kind,
                 {{"kdtree", AssociationKind::kKdTree}, {"projective", AssociationKind::kProjective}});
  node.read("max_distance", association.max_distance);
  node.read("window", association.window);
  node.reject_unread_keys();
  validated(node, [&] { validate(association); });
}

void read_convergence(const ConfigNode& node, ConvergenceConfig& convergence) {
  if (!node.is_map()) throw node.error("expected a map {max_iterations: ..., translation: ..., rotation: ...}");
  node.read("max_iterations", convergence.max_iterations);
  node.read("translation", convergence.translation);
  node.read("rotation", convergence.rotation);
  node.read("error_change", convergence.error_change);
  node.reject_unread_keys();
  validated(node, [&] { validate(convergence); });
}

// The scalar settings of the root map, each checked at its own line.
void read_scalars(const ConfigNode& node, PipelineConfig& config) {
  std::string matcher;
  if (node.read("matcher", matcher) && matcher != "pipeline") {
    throw node.at("matcher").error("this is a pipeline configuration: 'matcher' must be 'pipeline', not '" +
                                   matcher + "'");
  }
  node.read_enum("minimizer", config.minimizer,
                 {{"point_to_point", Minimizer::kPointToPoint},
                  {"point_to_line", Minimizer::kPointToLine},
                  {"point_to_plane", Minimizer::kPointToLine}});
  if (node.read("min_inliers", config.min_inliers) && config.min_inliers < 3) {
    throw node.at("min_inliers").error("min_inliers must be >= 3");
  }
  if (node.read("range_sigma", config.range_sigma) && !(config.range_sigma > 0.0)) {
    throw node.at("range_sigma").error("range_sigma must be > 0");
  }
}

}  // namespace

PipelineConfig pipeline_config_from(const ConfigNode& node) {
  PipelineConfig config;
  if (node.is_null()) return config;
  if (!node.is_map()) throw node.error("expected a map of pipeline settings");
  read_scalars(node, config);
  read_filters(node, "source_filters", config.source_filters, data_filter_kinds());
  read_filters(node, "target_filters", config.target_filters, data_filter_kinds());
  if (node.has("association")) read_association(node.at("association"), config.association);
  read_filters(node, "outlier_filters", config.outlier_filters, outlier_filter_kinds());
  if (node.has("convergence")) read_convergence(node.at("convergence"), config.convergence);
  node.reject_unread_keys();
  return config;
}

PipelineConfig load_pipeline_config(const std::string& yaml_path) {
  return pipeline_config_from(ConfigNode::load(yaml_path));
}

}  // namespace slam2d
