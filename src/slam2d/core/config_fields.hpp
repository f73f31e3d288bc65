// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One field table per config struct. Beside each config struct stands one function that names
// every field once, with its unit, allowed range and meaning:
//
//   template <typename Fields>
//   void describe(Fields& f, IcpConfig& c) {
//     f.number("max_iterations", c.max_iterations, "1", at_least(1), "registrations before giving up");
//     f.choice("solver", c.solver, "closed-form solver of each registration");
//     f.flag("accelerated", c.accelerated, "Besl & McKay's accelerated ICP");
//     f.section("kernel", c.kernel, "robust kernel on the residual");
//   }
//
// The default of a field is the struct's initialiser. Everything that needs the fields walks this
// one table with a visitor: check_fields() here (the ranges, for each validate()), read_config()
// in io/config_file.hpp (YAML presets, `--config`), io/config_text.hpp (`slam2d config dump`
// and the docs tables). An enum field's names come from one `choices(Enum)` function beside the
// enum, found by argument-dependent lookup:
//
//   constexpr auto choices(PointToPointSolver) {
//     return std::array{Choice{"svd", PointToPointSolver::kSvd}, Choice{"quaternion", PointToPointSolver::kQuaternion}};
//   }
//
// A visitor is any type with the members number(name, value, unit, range, doc) for double, int,
// std::uint64_t and std::size_t values, flag(name, bool, doc), choice(name, enum, doc),
// section(name, struct, doc) and list(name, std::vector<std::variant<...>>, doc) (a list of
// stages such as the ICP pipeline's filters: each alternative has a static `kind` name and a
// table); its `describe` recursion into a section or an item is its own business.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/core/number_text.hpp"

namespace slam2d {

/// The values a number field allows: an interval, each end open or closed, either end unbounded.
/// Numbers are finite unless `infinity_allowed` (then +inf, written .inf in YAML, is allowed too:
/// "no limit").
struct Range {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
  bool low_open = false;
  bool high_open = false;
  bool infinity_allowed = false;

  bool contains(double value) const {
    if (std::isinf(value) && value > 0.0 && infinity_allowed) return true;
    if (!std::isfinite(value)) return false;
    if (low_open ? !(value > low) : !(value >= low)) return false;
    return high_open ? value < high : value <= high;
  }
  /// "any", ">= 1", "> 0", "<= 5", "in [0, 1)"; "> 0 or .inf".
  std::string text() const { return infinity_allowed ? interval_text() + " or .inf" : interval_text(); }

 private:
  std::string interval_text() const {
    const bool bounded_low = std::isfinite(low);
    const bool bounded_high = std::isfinite(high);
    if (!bounded_low && !bounded_high) return "any";
    if (!bounded_high) return (low_open ? "> " : ">= ") + format_number(low);
    if (!bounded_low) return (high_open ? "< " : "<= ") + format_number(high);
    return std::string("in ") + (low_open ? "(" : "[") + format_number(low) + ", " + format_number(high) +
           (high_open ? ")" : "]");
  }
};

constexpr Range any_value() { return {}; }
/// `range`, and +inf ("no limit") too.
constexpr Range or_infinity(Range range) {
  range.infinity_allowed = true;
  return range;
}
constexpr Range at_least(double low) { return {.low = low}; }
constexpr Range greater_than(double low) { return {.low = low, .low_open = true}; }
constexpr Range at_most(double high) { return {.high = high}; }
/// [low, high]
constexpr Range between(double low, double high) { return {.low = low, .high = high}; }
/// [low, high)
constexpr Range closed_open(double low, double high) { return {.low = low, .high = high, .high_open = true}; }
/// (low, high]
constexpr Range open_closed(double low, double high) { return {.low = low, .high = high, .low_open = true}; }
/// (low, high)
constexpr Range open_interval(double low, double high) {
  return {.low = low, .high = high, .low_open = true, .high_open = true};
}

/// One name of an enum value, for choices(Enum).
template <typename Enum>
struct Choice {
  std::string_view name;
  Enum value;
};
template <typename Enum>
Choice(const char*, Enum) -> Choice<Enum>;

/// The name choices(Enum) gives `value`; "?" for a value without one.
template <typename Enum>
std::string_view choice_name(Enum value) {
  for (const auto& choice : choices(value)) {
    if (choice.value == value) return choice.name;
  }
  return "?";
}

/// "a, b, c": the `kind` of each alternative of a list's variant.
template <typename... Kinds>
std::string kind_list(const std::variant<Kinds...>*) {
  std::string list;
  ((list += (list.empty() ? "" : ", ") + std::string(Kinds::kind)), ...);
  return list;
}

/// Every name of the enum with its value, for a command-line option's transformer.
template <typename Enum>
std::map<std::string, Enum> choice_map() {
  std::map<std::string, Enum> map;
  for (const auto& choice : choices(Enum{})) map.emplace(choice.name, choice.value);
  return map;
}

/// "a, b, c": every name of the enum, for messages and docs.
template <typename Enum>
std::string choice_list() {
  std::string list;
  for (const auto& choice : choices(Enum{})) {
    if (!list.empty()) list += ", ";
    list += choice.name;
  }
  return list;
}

/// A number field's value as text: integers exactly, doubles in their shortest exact form.
template <typename Number>
std::string number_text(Number value) {
  if constexpr (std::is_integral_v<Number>) {
    return std::to_string(value);
  } else {
    return std::isinf(value) ? (value > 0 ? ".inf" : "-.inf") : format_number(value);
  }
}

/// A field table visitor that checks each number against its range; the error names the
/// struct, the field's path and the range ("HectorSlamConfig.matcher.fine_iterations = 0: must be >= 1").
class FieldChecker {
 public:
  explicit FieldChecker(std::string prefix) : prefix_(std::move(prefix)) {}

  template <typename Number>
  void number(std::string_view name, const Number& value, std::string_view /*unit*/, const Range& range,
              std::string_view /*doc*/) {
    if (!range.contains(static_cast<double>(value))) {
      throw Error(prefix_ + "." + std::string(name) + " = " + number_text(value) + ": must be " +
                  (range.text() == "any" ? std::string("finite") : range.text()));
    }
  }
  void flag(std::string_view, const bool&, std::string_view) {}
  template <typename Enum>
  void choice(std::string_view name, const Enum& value, std::string_view) {
    if (choice_name(value) == "?") throw Error(prefix_ + "." + std::string(name) + ": not one of " + choice_list<Enum>());
  }
  template <typename Section>
  void section(std::string_view name, Section& value, std::string_view) {
    FieldChecker inner(prefix_ + "." + std::string(name));
    describe(inner, value);
  }
  template <typename... Kinds>
  void list(std::string_view name, std::vector<std::variant<Kinds...>>& items, std::string_view) {
    for (std::size_t i = 0; i < items.size(); ++i) {
      FieldChecker inner(prefix_ + "." + std::string(name) + "[" + std::to_string(i) + "]");
      std::visit([&](auto& item) { describe(inner, item); }, items[i]);
    }
  }

 private:
  std::string prefix_;
};

/// Throws Error at the first field of `config` outside its range (each validate() starts here,
/// then checks what involves several fields). `name` is the struct's, for the message.
template <typename Config>
void check_fields(const Config& config, std::string_view name) {
  Config copy = config;  // describe() takes the fields by reference
  FieldChecker checker{std::string(name)};
  describe(checker, copy);
}

}  // namespace slam2d
