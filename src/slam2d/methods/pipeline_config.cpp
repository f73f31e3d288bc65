// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/methods/pipeline_config.hpp"

#include <string>

namespace slam2d {

PipelineConfig pipeline_config_from(const ConfigNode& node) {
  PipelineConfig config;
  std::string matcher;
  if (node.is_map() && node.read("matcher", matcher) && matcher != "pipeline") {
    throw node.at("matcher").error("this is a pipeline configuration: 'matcher' must be 'pipeline', not '" + matcher + "'");
  }
  read_valid_config(node, config);  // the field tables of PipelineConfig and of each filter
  return config;
}

PipelineConfig load_pipeline_config(const std::string& yaml_path) {
  return pipeline_config_from(ConfigNode::load(yaml_path));
}

}  // namespace slam2d
