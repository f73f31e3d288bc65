// SPDX-License-Identifier: BSD-3-Clause
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
// ParseError naming the file and the line of the offending value. A config struct with a field
// table (core/config_fields.hpp) is read whole, sections as nested maps, each number checked
// against its range and every key not in the table refused:
//
//   GraphSlamConfig config;                   // the defaults, overridden by the file's keys
//   read_config(ConfigNode::load("configs/graph.yaml").at("graph"), config);

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <type_traits>
#include <memory>
#include <optional>
#include <variant>
#include <string>
#include <utility>
#include <vector>

#include "slam2d/core/config_fields.hpp"
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
  long long as_integer_or(long long fallback) const;  // fallback when the scalar is not a long long
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

/// The field table visitor behind read_config(): each field present in the node is read and
/// checked against its range (ParseError at the value's line), sections recurse into nested maps.
class ConfigReader {
 public:
  explicit ConfigReader(const ConfigNode& node) : node_(node) {}

  template <typename Number>
  void number(std::string_view name, Number& value, std::string_view /*unit*/, const Range& range,
              std::string_view /*doc*/) {
    const std::string key(name);
    Number read_value = value;
    if constexpr (std::is_floating_point_v<Number>) {
      if (range.infinity_allowed && node_.has(key) && node_.at(key).is_scalar() && node_.at(key).as_string() == ".inf") {
        value = std::numeric_limits<Number>::infinity();
        return;
      }
    }
    if (!read_number(key, read_value)) return;
    if (!range.contains(static_cast<double>(read_value))) {
      throw node_.at(key).error("'" + key + "' = " + number_text(read_value) + " is out of range (must be " +
                                range.text() + ")");
    }
    value = read_value;
  }
  void flag(std::string_view name, bool& value, std::string_view) { node_.read(std::string(name), value); }
  template <typename Enum>
  void choice(std::string_view name, Enum& value, std::string_view) {
    const std::string key(name);
    std::string text;
    if (!node_.read(key, text)) return;
    for (const auto& option : choices(value)) {
      if (option.name == text) {
        value = option.value;
        return;
      }
    }
    throw node_.at(key).error("unknown value '" + text + "' for '" + key + "' (expected one of: " + choice_list<Enum>() + ")");
  }
  template <typename Section>
  void section(std::string_view name, Section& value, std::string_view) {
    const std::string key(name);
    if (!node_.has(key)) return;
    const ConfigNode child = node_.at(key);
    if (!child.is_map()) throw child.error("'" + key + "' must be a map of settings");
    ConfigReader inner(child);
    describe(inner, value);
    child.reject_unread_keys();
  }
  /// A list of {kind: NAME, <that kind's fields>...}; present, it replaces the whole list (null: empty).
  template <typename... Kinds>
  void list(std::string_view name, std::vector<std::variant<Kinds...>>& items, std::string_view) {
    const std::string key(name);
    if (!node_.has(key)) return;
    const ConfigNode list = node_.at(key);
    std::vector<std::variant<Kinds...>> read_items;
    if (!list.is_null()) {
      for (const ConfigNode& item : list.items()) read_items.push_back(read_item<Kinds...>(item));
    }
    items = std::move(read_items);
  }

 private:
  bool read_number(const std::string& key, double& value) const { return node_.read(key, value); }
  bool read_number(const std::string& key, int& value) const { return node_.read(key, value); }
  template <typename Unsigned>
    requires std::is_unsigned_v<Unsigned>
  bool read_number(const std::string& key, Unsigned& value) const {
    std::uint64_t wide = value;
    if (!node_.read(key, wide)) return false;
    if (wide > std::numeric_limits<Unsigned>::max()) throw node_.at(key).error("'" + key + "' is too large");
    value = static_cast<Unsigned>(wide);
    return true;
  }
  template <typename... Kinds>
  static std::variant<Kinds...> read_item(const ConfigNode& item) {
    using Item = std::variant<Kinds...>;
    if (!item.is_map()) throw item.error("expected {kind: ..., ...}");
    std::string kind;
    if (!item.read("kind", kind)) throw item.error("a list item needs a 'kind'");
    std::optional<Item> value;
    ((kind == Kinds::kind ? void(value.emplace(Kinds{})) : void()), ...);
    if (!value) {
      throw item.at("kind").error("unknown kind '" + kind + "' (expected one of: " +
                                  kind_list(static_cast<const Item*>(nullptr)) + ")");
    }
    ConfigReader inner(item);
    std::visit([&](auto& alternative) { describe(inner, alternative); }, *value);
    item.reject_unread_keys();
    return *value;
  }
  const ConfigNode& node_;
};

/// Reads the keys of `node` (a map; a null node reads nothing) into `config` by its field table;
/// fields not in the node keep their value. ParseError, at its line, on a key not in the table,
/// a wrong type or a value out of range.
template <typename Config>
void read_config(const ConfigNode& node, Config& config) {
  if (node.is_null()) return;
  if (!node.is_map()) throw node.error("expected a map of settings");
  ConfigReader reader(node);
  describe(reader, config);
  node.reject_unread_keys();
}

/// read_config(), then the struct's validate() (what involves several fields; check_fields for a
/// struct without one), its Error turned into a ParseError at `node`: a preset that passes is a
/// config the method accepts.
template <typename Config>
void read_valid_config(const ConfigNode& node, Config& config) {
  read_config(node, config);
  try {
    if constexpr (requires { validate(config); }) {
      validate(config);
    } else {
      check_fields(config, "config");
    }
  } catch (const ParseError&) {
    throw;
  } catch (const Error& e) {
    throw node.error(e.what());
  }
}

}  // namespace slam2d
