// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/input_limits.hpp"

#include <algorithm>
#include <cstdlib>
#include <string>

#include "slam2d/io/config_file.hpp"

namespace slam2d {

InputLimits parse_input_limits(const std::string& text, const std::string& source) {
  // "a=1,b=2" as the YAML "a: 1\nb: 2", read by the field table.
  std::string yaml;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    std::string item = text.substr(start, end - start);
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (!item.empty()) {
      const std::size_t equals = item.find('=');
      check(equals != std::string::npos && equals > 0, source + ": '" + item + "' is not KEY=VALUE");
      yaml += item.substr(0, equals) + ": " + item.substr(equals + 1) + "\n";
    }
    start = end + 1;
  }
  InputLimits limits;
  if (!yaml.empty()) read_valid_config(ConfigNode::parse(yaml, source), limits);
  return limits;
}

const InputLimits& input_limits() {
  static const InputLimits limits = [] {
    const char* text = std::getenv("SLAM2D_LIMITS");
    return parse_input_limits(text == nullptr ? "" : text);
  }();
  return limits;
}

void check_beam_count(std::size_t beams) {
  if (beams > input_limits().max_beams) {
    throw Error("a scan of " + std::to_string(beams) + " beams is over max_beams (" +
                std::to_string(input_limits().max_beams) + "; " + limit_hint("max_beams") + ")");
  }
}

std::string limit_hint(const char* key) { return std::string("raise it with SLAM2D_LIMITS=") + key + "=..."; }

}  // namespace slam2d
