#pragma once
// Configuration files: YAML documents (read with yaml-cpp, seen only in io) as a tree of
// ConfigNode values that report errors as "PATH:LINE: message" and catch misspelt keys.
//
//   const ConfigNode root = ConfigNode::load("configs/pl-icp.yaml");
//   root.read("max_iterations", config.max_iterations);   // only if the key is present
//   root.read_enum("search", config.search, {{"projective", Search::kProjective}, {"kdtree", Search::kKdTree}});
//   root.reject_unread_keys();   // ParseError at the first key nobody read
//
// Every read checks the type and the value (finite numbers, integers in range) and throws
// ParseError naming the file and the line of the offending value.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "slam2d/core/error.hpp"

namespace slam2d {

class ConfigNode {
 public:
  /// Parses a YAML file. Throws Error when it cannot be read, ParseError when it is not YAML.
  static ConfigNode load(const std::string& path);
  /// Parses YAML text; `name` stands for the path in messages.
  static ConfigNode parse(const std::string& text, const std::string& name = "<config>");

  ConfigNode();
  ~ConfigNode();
  ConfigNode(const ConfigNode&);
  ConfigNode& operator=(const ConfigNode&);
  ConfigNode(ConfigNode&&) noexcept;
  ConfigNode& operator=(ConfigNode&&) noexcept;

  bool is_map() const;
  bool is_list() const;
  bool is_scalar() const;
  bool is_null() const;

  /// Map access. has() does not mark the key as read; at() and the reads do.
  bool has(const std::string& key) const;
  ConfigNode at(const std::string& key) const;  // ParseError when missing
  std::vector<std::string> keys() const;         // in file order
  /// List access (ParseError when this is not a list).
  std::vector<ConfigNode> items() const;

  /// Scalar conversions (ParseError on a wrong type or a non-finite number).
  double as_double() const;
  long long as_integer() const;
  bool as_bool() const;
  std::string as_string() const;

  /// Reads `key` into `value` when present (value unchanged otherwise); returns whether it was.
  bool read(const std::string& key, double& value) const;
  bool read(const std::string& key, int& value) const;
  bool read(const std::string& key, std::uint64_t& value) const;  // >= 0 (also std::size_t, seeds)
  bool read(const std::string& key, bool& value) const;
  bool read(const std::string& key, std::string& value) const;
  /// Reads a string key and maps it through `names` (ParseError listing the names otherwise).
  template <typename Enum>
  bool read_enum(const std::string& key, Enum& value, const std::vector<std::pair<std::string, Enum>>& names) const {
    std::string text;
    if (!read(key, text)) return false;
    for (const auto& [name, option] : names) {
      if (name == text) {
        value = option;
        return true;
      }
    }
    std::string known;
    for (const auto& entry : names) known += (known.empty() ? "" : ", ") + entry.first;
    throw at(key).error("unknown value '" + text + "' for '" + key + "' (expected one of: " + known + ")");
  }

  /// Throws ParseError at the first key of this map (not of child maps) that no read, at() or
  /// mark_read() has touched: a misspelt or unsupported setting.
  void reject_unread_keys() const;
  void mark_read(const std::string& key) const;

  /// An error located at this node.
  ParseError error(const std::string& message) const;
  const std::string& path() const;
  std::size_t line() const;  // 1-based; 0 when unknown

 private:
  struct Impl;
  explicit ConfigNode(std::shared_ptr<Impl> impl);
  ConfigNode child(const std::string& key) const;
  std::shared_ptr<Impl> impl_;
};

}  // namespace slam2d
