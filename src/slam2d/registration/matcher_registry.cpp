#include "slam2d/registration/matcher_registry.hpp"

#include <algorithm>
#include <functional>
#include <map>

#include "slam2d/core/error.hpp"
#include "slam2d/registration/correlative.hpp"
#include "slam2d/registration/ga_icp.hpp"
#include "slam2d/registration/icp.hpp"
#include "slam2d/registration/idc.hpp"
#include "slam2d/registration/pipeline.hpp"
#include "slam2d/registration/pipeline_config.hpp"
#include "slam2d/registration/pl_icp.hpp"
#include "slam2d/registration/point_to_plane.hpp"
#include "slam2d/registration/tangent_search.hpp"
#include "slam2d/registration/trimmed_icp.hpp"
#include "slam2d/registration/weighted_icp.hpp"

namespace slam2d {
namespace {

// The fields of each config, read from a preset under their own names.

void read_fields(const ConfigNode& n, IcpConfig& c) {
  n.read("max_iterations", c.max_iterations);
  n.read("max_correspondence_distance", c.max_correspondence_distance);
  n.read("min_correspondences", c.min_correspondences);
  n.read_enum("solver", c.solver, {{"svd", PointToPointSolver::kSvd}, {"quaternion", PointToPointSolver::kQuaternion}});
  n.read("min_mse_change", c.min_mse_change);
  n.read("min_translation_step", c.min_translation_step);
  n.read("min_rotation_step", c.min_rotation_step);
  n.read("accelerated", c.accelerated);
  n.read("acceleration_angle", c.acceleration_angle);
  n.read("acceleration_max_factor", c.acceleration_max_factor);
}

void read_fields(const ConfigNode& n, TrimmedIcpConfig& c) {
  n.read("overlap", c.overlap);
  n.read("min_overlap", c.min_overlap);
  n.read("lambda", c.lambda);
  n.read_enum("overlap_estimation", c.overlap_estimation,
              {{"at_convergence", OverlapEstimation::kAtConvergence}, {"per_iteration", OverlapEstimation::kPerIteration}});
  n.read("max_iterations", c.max_iterations);
  n.read("min_trimmed_mse", c.min_trimmed_mse);
  n.read("min_relative_change", c.min_relative_change);
  n.read("min_correspondences", c.min_correspondences);
  n.read_enum("solver", c.solver, {{"svd", PointToPointSolver::kSvd}, {"quaternion", PointToPointSolver::kQuaternion}});
}

void read_fields(const ConfigNode& n, PointToPlaneConfig& c) {
  n.read("max_iterations", c.max_iterations);
  n.read("max_correspondence_distance", c.max_correspondence_distance);
  n.read("min_correspondences", c.min_correspondences);
  n.read("min_translation_step", c.min_translation_step);
  n.read("min_rotation_step", c.min_rotation_step);
  n.read("normal_neighbors", c.normal_neighbors);
  n.read("normal_max_distance", c.normal_max_distance);
  n.read("normal_min_neighbors", c.normal_min_neighbors);
}

void read_fields(const ConfigNode& n, PlIcpConfig& c) {
  n.read("max_iterations", c.max_iterations);
  n.read("epsilon_xy", c.epsilon_xy);
  n.read("epsilon_theta", c.epsilon_theta);
  n.read("max_correspondence_distance", c.max_correspondence_distance);
  n.read("max_segment_length", c.max_segment_length);
  n.read("outliers_max_fraction", c.outliers_max_fraction);
  n.read("outliers_adaptive_order", c.outliers_adaptive_order);
  n.read("outliers_adaptive_mult", c.outliers_adaptive_mult);
  n.read("outliers_remove_doubles", c.outliers_remove_doubles);
  n.read_enum("search", c.search, {{"projective", PlIcpSearch::kProjective}, {"kdtree", PlIcpSearch::kKdTree}});
  n.read("min_correspondences", c.min_correspondences);
  n.read("range_sigma", c.range_sigma);
}

void read_fields(const ConfigNode& n, ImrpConfig& c) {
  n.read("max_iterations", c.max_iterations);
  n.read("window_initial", c.window_initial);
  n.read("window_final", c.window_final);
  n.read("window_decay", c.window_decay);
  n.read("max_range_difference", c.max_range_difference);
  n.read("max_gap", c.max_gap);
  n.read("final_max_distance", c.final_max_distance);
  n.read("translation_tolerance", c.translation_tolerance);
  n.read("rotation_tolerance", c.rotation_tolerance);
  n.read("min_correspondences", c.min_correspondences);
  n.read("range_sigma", c.range_sigma);
}

void read_fields(const ConfigNode& n, IdcConfig& c) {
  n.read("max_iterations", c.max_iterations);
  n.read("window_initial", c.window_initial);
  n.read("window_final", c.window_final);
  n.read("window_decay", c.window_decay);
  n.read("max_distance_initial", c.max_distance_initial);
  n.read("max_distance_final", c.max_distance_final);
  n.read("max_distance_decay", c.max_distance_decay);
  n.read("max_range_difference", c.max_range_difference);
  n.read("max_gap", c.max_gap);
  n.read("translation_tolerance", c.translation_tolerance);
  n.read("rotation_tolerance", c.rotation_tolerance);
  n.read("min_correspondences", c.min_correspondences);
  n.read("range_sigma", c.range_sigma);
}

void read_fields(const ConfigNode& n, WeightedIcpConfig& c) {
  n.read_enum("weighting", c.weighting, {{"boolean", IcpWeighting::kBoolean}, {"soft", IcpWeighting::kSoft}});
  n.read("select_every", c.select_every);
  n.read("weight_distance", c.weight_distance);
  n.read_enum("soft_kernel", c.soft_kernel,
              {{"linear", SoftWeightKernel::kLinear}, {"gaussian", SoftWeightKernel::kGaussian}, {"cauchy", SoftWeightKernel::kCauchy}});
  n.read("max_correspondence_distance", c.max_correspondence_distance);
  n.read("reject_sigma_factor", c.reject_sigma_factor);
  n.read("max_normal_angle", c.max_normal_angle);
  n.read_enum("metric", c.metric, {{"point_to_point", ErrorMetric::kPointToPoint}, {"point_to_line", ErrorMetric::kPointToLine}});
  n.read("normal_neighbors", c.normal_neighbors);
  n.read("normal_max_distance", c.normal_max_distance);
  n.read("max_iterations", c.max_iterations);
  n.read("translation_tolerance", c.translation_tolerance);
  n.read("rotation_tolerance", c.rotation_tolerance);
  n.read("min_correspondences", c.min_correspondences);
  n.read("range_sigma", c.range_sigma);
}

void read_fields(const ConfigNode& n, GaIcpConfig& c) {
  n.read("window_x", c.window_x);
  n.read("window_y", c.window_y);
  n.read("window_theta", c.window_theta);
  n.read("bits_per_gene", c.bits_per_gene);
  n.read("population", c.population);
  n.read("generations", c.generations);
  n.read("crossover_rate", c.crossover_rate);
  n.read("mutation_rate", c.mutation_rate);
  n.read("elite", c.elite);
  n.read("tournament_size", c.tournament_size);
  n.read("seed", c.seed);
  n.read("max_range_difference", c.max_range_difference);
  n.read("min_overlap", c.min_overlap);
  n.read("angular_resolution", c.angular_resolution);
  n.read("icp_max_iterations", c.icp_max_iterations);
  n.read("icp_max_correspondence_distance", c.icp_max_correspondence_distance);
  n.read("icp_min_correspondences", c.icp_min_correspondences);
}

void read_fields(const ConfigNode& n, CorrelativeConfig& c) {
  n.read("resolution", c.resolution);
  n.read("sigma", c.sigma);
  n.read("truncation", c.truncation);
  n.read("max_segment_length", c.max_segment_length);
  n.read("levels", c.levels);
  n.read("window_x", c.window_x);
  n.read("window_y", c.window_y);
  n.read("window_theta", c.window_theta);
  n.read("linear_step", c.linear_step);
  n.read("angular_step", c.angular_step);
  n.read_enum("search", c.search,
              {{"exhaustive", CorrelativeSearch::kExhaustive},
               {"multi_resolution", CorrelativeSearch::kMultiResolution},
               {"branch_and_bound", CorrelativeSearch::kBranchAndBound}});
  n.read("low_resolution_steps", c.low_resolution_steps);
  n.read("min_score", c.min_score);
  n.read("covariance_radius", c.covariance_radius);
  n.read("min_eigenvalue_ratio", c.min_eigenvalue_ratio);
}

// The cloud-to-cloud overload of a matcher that also has others (prebuilt tables or trees).
template <typename Config>
auto cloud_matcher(MatchResult (*match)(const PointCloud2&, const PointCloud2&, const SE2&, const Config&)) {
  return match;
}

// A matcher bound to a config read from `node` (validated now, so a bad preset fails at load).
template <typename Config, typename Match>
Matcher bind(const ConfigNode& node, Config config, Match match) {
  read_fields(node, config);
  node.reject_unread_keys();
  validate(config);
  return [config, match](const PointCloud2& target, const PointCloud2& source, const SE2& guess) {
    return match(target, source, guess, config);
  };
}

using Factory = std::function<Matcher(const ConfigNode&)>;

const std::vector<std::pair<std::string, Factory>>& factories() {
  static const std::vector<std::pair<std::string, Factory>> table{
      {"icp", [](const ConfigNode& n) { return bind(n, IcpConfig{}, match_icp); }},
      {"icp-accelerated", [](const ConfigNode& n) { return bind(n, IcpConfig{.accelerated = true}, match_icp); }},
      {"trimmed-icp", [](const ConfigNode& n) { return bind(n, TrimmedIcpConfig{}, match_trimmed_icp); }},
      {"pl-icp", [](const ConfigNode& n) { return bind(n, PlIcpConfig{}, match_pl_icp); }},
      {"point-to-plane", [](const ConfigNode& n) { return bind(n, PointToPlaneConfig{}, cloud_matcher<PointToPlaneConfig>(match_point_to_plane)); }},
      {"imrp", [](const ConfigNode& n) { return bind(n, ImrpConfig{}, match_imrp); }},
      {"idc", [](const ConfigNode& n) { return bind(n, IdcConfig{}, match_idc); }},
      {"tangent-search", [](const ConfigNode& n) { return bind(n, TangentSearchConfig{}, match_tangent_search); }},
      {"boolean-icp", [](const ConfigNode& n) { return bind(n, WeightedIcpConfig{}, match_boolean_icp); }},
      {"soft-icp", [](const ConfigNode& n) { return bind(n, WeightedIcpConfig{.weighting = IcpWeighting::kSoft}, match_soft_icp); }},
      {"ga-icp", [](const ConfigNode& n) { return bind(n, GaIcpConfig{}, match_ga_icp); }},
      {"correlative", [](const ConfigNode& n) { return bind(n, CorrelativeConfig{}, cloud_matcher<CorrelativeConfig>(match_correlative)); }},
      {"pipeline", [](const ConfigNode& n) {
         const PipelineConfig config = n.is_null() ? PipelineConfig{} : pipeline_config_from(n);
         validate(config);
         return Matcher([config](const PointCloud2& target, const PointCloud2& source, const SE2& guess) {
           return match_pipeline(target, source, guess, config);
         });
       }},
  };
  return table;
}

const Factory& factory(const std::string& name) {
  for (const auto& [known, make] : factories()) {
    if (known == name) return make;
  }
  std::string list;
  for (const std::string& known : matcher_names()) list += (list.empty() ? "" : ", ") + known;
  throw Error("unknown matcher '" + name + "' (known: " + list + ")");
}

}  // namespace

const std::vector<std::string>& matcher_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& entry : factories()) out.push_back(entry.first);
    return out;
  }();
  return names;
}

Matcher make_matcher(const std::string& name) { return factory(name)(ConfigNode()); }

Matcher make_matcher(const std::string& name, const ConfigNode& config) {
  const Factory& make = factory(name);
  std::string named = name;
  if (config.read("matcher", named) && named != name) {
    throw config.at("matcher").error("this preset is for matcher '" + named + "', not '" + name + "'");
  }
  return make(config);
}

Matcher load_matcher(const std::string& yaml_path) {
  const ConfigNode config = ConfigNode::load(yaml_path);
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
