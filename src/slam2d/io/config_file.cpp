// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/config_file.hpp"

#include <charconv>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace slam2d {

struct ConfigNode::Impl {
  YAML::Node node;
  std::string path;
  std::size_t line = 0;
  std::set<std::string> read_keys;                         // map keys touched so far
  std::map<std::string, std::shared_ptr<Impl>> children;  // cached, so read marks persist
  std::vector<std::shared_ptr<Impl>> items;                // cached list items
  bool items_built = false;

  Impl(YAML::Node yaml, std::string file, std::size_t fallback_line) : node(std::move(yaml)), path(std::move(file)) {
    const YAML::Mark mark = node.Mark();
    line = mark.line >= 0 ? static_cast<std::size_t>(mark.line) + 1 : fallback_line;
  }
};

ConfigNode::ConfigNode() : impl_(std::make_shared<Impl>(YAML::Node(), "<config>", 0)) {}
ConfigNode::ConfigNode(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}
ConfigNode::~ConfigNode() = default;
ConfigNode::ConfigNode(const ConfigNode&) = default;
ConfigNode& ConfigNode::operator=(const ConfigNode&) = default;
ConfigNode::ConfigNode(ConfigNode&&) noexcept = default;
ConfigNode& ConfigNode::operator=(ConfigNode&&) noexcept = default;

ConfigNode ConfigNode::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open configuration file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

ConfigNode ConfigNode::parse(const std::string& text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ParseError(name, e.mark.line >= 0 ? static_cast<std::size_t>(e.mark.line) + 1 : 0, e.msg);
  }
  ConfigNode node(std::make_shared<Impl>(root, name, 1));
  if (!node.is_map() && !node.is_null()) throw node.error("a configuration file must be a map of keys to values");
  return node;
}

bool ConfigNode::is_map() const { return impl_->node.IsMap(); }
bool ConfigNode::is_list() const { return impl_->node.IsSequence(); }
bool ConfigNode::is_scalar() const { return impl_->node.IsScalar(); }
bool ConfigNode::is_null() const { return !impl_->node.IsDefined() || impl_->node.IsNull(); }

bool ConfigNode::has(const std::string& key) const { return is_map() && impl_->node[key].IsDefined(); }

ConfigNode ConfigNode::child(const std::string& key) const {
  auto found = impl_->children.find(key);
  if (found == impl_->children.end()) {
    found = impl_->children.emplace(key, std::make_shared<Impl>(impl_->node[key], impl_->path, impl_->line)).first;
  }
  return ConfigNode(found->second);
}

ConfigNode ConfigNode::at(const std::string& key) const {
  if (!is_map()) throw error("expected a map with key '" + key + "'");
  if (!has(key)) throw error("missing key '" + key + "'");
  mark_read(key);
  return child(key);
}

namespace {

// A mapping's key as a name; a key that is itself a list or a mapping (YAML's "? [a, b]: value",
// found by fuzzing) is a ParseError at its line, not yaml-cpp's conversion error.
std::string key_name(const YAML::Node& key, const std::string& path, std::size_t fallback_line) {
  if (!key.IsScalar()) {
    const YAML::Mark mark = key.Mark();
    throw ParseError(path, mark.line >= 0 ? static_cast<std::size_t>(mark.line) + 1 : fallback_line,
                     "a key must be a name, not a list or a mapping");
  }
  return key.Scalar();
}

}  // namespace

std::vector<std::string> ConfigNode::keys() const {
  std::vector<std::string> out;
  if (!is_map()) return out;
  for (const auto& entry : impl_->node) out.push_back(key_name(entry.first, impl_->path, impl_->line));
  return out;
}

std::vector<ConfigNode> ConfigNode::items() const {
  if (!is_list()) throw error("expected a list");
  if (!impl_->items_built) {
    for (const YAML::Node& item : impl_->node) impl_->items.push_back(std::make_shared<Impl>(item, impl_->path, impl_->line));
    impl_->items_built = true;
  }
  std::vector<ConfigNode> out;
  for (const auto& item : impl_->items) out.push_back(ConfigNode(item));
  return out;
}

double ConfigNode::as_double() const {
  if (!is_scalar()) throw error("expected a number");
  double value = 0.0;
  if (!YAML::convert<double>::decode(impl_->node, value) || !std::isfinite(value)) {
    throw error("expected a finite number, got '" + impl_->node.Scalar() + "'");
  }
  return value;
}

long long ConfigNode::as_integer() const {
  if (!is_scalar()) throw error("expected an integer");
  long long value = 0;
  if (!YAML::convert<long long>::decode(impl_->node, value)) {
    throw error("expected an integer, got '" + impl_->node.Scalar() + "'");
  }
  return value;
}

long long ConfigNode::as_integer_or(long long fallback) const {
  if (!is_scalar()) throw error("expected an integer");
  long long value = 0;
  return YAML::convert<long long>::decode(impl_->node, value) ? value : fallback;
}

bool ConfigNode::as_bool() const {
  bool value = false;
  if (!is_scalar() || !YAML::convert<bool>::decode(impl_->node, value)) {
    throw error("expected true or false, got '" + (is_scalar() ? impl_->node.Scalar() : std::string("a non-scalar")) + "'");
  }
  return value;
}

std::string ConfigNode::as_string() const {
  if (!is_scalar()) throw error("expected a string");
  return impl_->node.Scalar();
}

bool ConfigNode::read(const std::string& key, double& value) const {
  if (!has(key)) return false;
  value = at(key).as_double();
  return true;
}

bool ConfigNode::read(const std::string& key, int& value) const {
  if (!has(key)) return false;
  const ConfigNode node = at(key);
  const long long v = node.as_integer();
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) throw node.error("integer out of range");
  value = static_cast<int>(v);
  return true;
}

bool ConfigNode::read(const std::string& key, std::uint64_t& value) const {
  if (!has(key)) return false;
  const ConfigNode node = at(key);
  const long long v = node.as_integer_or(-1);  // the whole unsigned range does not fit a long long
  if (v >= 0) {
    value = static_cast<std::uint64_t>(v);
    return true;
  }
  const std::string text = node.as_string();
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw node.error("expected a non-negative integer for '" + key + "', got '" + text + "'");
  }
  return true;
}

bool ConfigNode::read(const std::string& key, bool& value) const {
  if (!has(key)) return false;
  value = at(key).as_bool();
  return true;
}

bool ConfigNode::read(const std::string& key, std::string& value) const {
  if (!has(key)) return false;
  value = at(key).as_string();
  return true;
}

void ConfigNode::mark_read(const std::string& key) const { impl_->read_keys.insert(key); }

void ConfigNode::reject_unread_keys() const {
  if (!is_map()) return;
  for (const auto& entry : impl_->node) {
    const std::string key = key_name(entry.first, impl_->path, impl_->line);
    if (impl_->read_keys.count(key) == 0) {
      const YAML::Mark mark = entry.first.Mark();
      throw ParseError(impl_->path, mark.line >= 0 ? static_cast<std::size_t>(mark.line) + 1 : impl_->line,
                       "unknown key '" + key + "'");
    }
  }
}

ParseError ConfigNode::error(const std::string& message) const { return ParseError(impl_->path, impl_->line, message); }
const std::string& ConfigNode::path() const { return impl_->path; }
std::size_t ConfigNode::line() const { return impl_->line; }

}  // namespace slam2d
