// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A config struct as text, from its field table (core/config_fields.hpp): a commented YAML
// document that read_config() reads back to the same values (`slam2d config dump`, the presets
// in configs/), and a Markdown table of every field with its default, unit, range and meaning
// (the docs' configuration tables).

#include <cstddef>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/number_text.hpp"

namespace slam2d {

/// One field of a walked table: its dotted path, value as YAML text and its description.
struct FieldRow {
  std::string path;    // "matcher.fine_iterations"
  std::string value;   // "5", "svd", "true"; empty for a section
  std::string unit;    // "m", "rad", "1"; empty for flags, choices and sections
  std::string range;   // ">= 1", "svd | quaternion"; empty for flags and sections
  std::string doc;
  int depth = 0;       // nesting of sections
  bool is_section = false;  // a section, or a non-empty list (its items follow)
  bool list_item = false;   // the first row of a list item (its kind): "- kind: NAME" in YAML

  bool operator==(const FieldRow&) const = default;
};

/// The visitor that lists the fields in table order.
class FieldLister {
 public:
  explicit FieldLister(std::vector<FieldRow>& rows, std::string prefix = {}, int depth = 0)
      : rows_(rows), prefix_(std::move(prefix)), depth_(depth) {}

  template <typename Number>
  void number(std::string_view name, const Number& value, std::string_view unit, const Range& range,
              std::string_view doc) {
    rows_.push_back({path(name), number_text(value), std::string(unit), range.text(),
                     std::string(doc), depth_});
  }
  void flag(std::string_view name, const bool& value, std::string_view doc) {
    rows_.push_back({path(name), value ? "true" : "false", "", "", std::string(doc), depth_});
  }
  template <typename Enum>
  void choice(std::string_view name, const Enum& value, std::string_view doc) {
    std::string names;
    for (const auto& option : choices(value)) names += (names.empty() ? "" : " | ") + std::string(option.name);
    rows_.push_back({path(name), std::string(choice_name(value)), "", names, std::string(doc), depth_});
  }
  template <typename Section>
  void section(std::string_view name, Section& value, std::string_view doc) {
    rows_.push_back({path(name), "", "", "", std::string(doc), depth_, true});
    FieldLister inner(rows_, path(name), depth_ + 1);
    describe(inner, value);
  }
  template <typename... Kinds>
  void list(std::string_view name, std::vector<std::variant<Kinds...>>& items, std::string_view doc) {
    const std::string kinds = kind_list(static_cast<const std::variant<Kinds...>*>(nullptr));
    rows_.push_back({path(name), items.empty() ? "[]" : "", "", "list of: " + kinds, std::string(doc), depth_, !items.empty()});
    for (std::size_t i = 0; i < items.size(); ++i) {
      const std::string item_path = path(name) + "[" + std::to_string(i) + "]";
      std::visit(
          [&](auto& item) {
            rows_.push_back({item_path + ".kind", std::string(item.kind), "", kinds, "", depth_ + 1, false, true});
            FieldLister inner(rows_, item_path, depth_ + 2);
            describe(inner, item);
          },
          items[i]);
    }
  }

 private:
  std::string path(std::string_view name) const { return prefix_.empty() ? std::string(name) : prefix_ + "." + std::string(name); }
  std::vector<FieldRow>& rows_;
  std::string prefix_;
  int depth_;
};

/// Every field of `config` (with its current values) in table order, sections before their fields.
template <typename Config>
std::vector<FieldRow> field_rows(const Config& config) {
  Config copy = config;
  std::vector<FieldRow> rows;
  FieldLister lister(rows);
  describe(lister, copy);
  return rows;
}

/// The rows as a YAML document, each value commented with its unit, range and meaning, nested
/// under `indent` spaces (for a document whose top-level key holds the config).
std::string config_yaml(const std::vector<FieldRow>& rows, int indent = 0);
/// The rows as a Markdown table: field, default, unit, range, meaning.
std::string config_markdown(const std::vector<FieldRow>& rows);

}  // namespace slam2d
