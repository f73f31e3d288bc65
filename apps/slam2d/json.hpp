// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A minimal JSON object writer for --json summaries: flat or nested objects of numbers, strings,
// booleans and nulls. Numbers are written in their shortest exact form; NaN and inf become null.

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace slam2d::cli {

class JsonObject {
 public:
  JsonObject& add(std::string_view key, double value);
  JsonObject& add(std::string_view key, std::size_t value);
  JsonObject& add(std::string_view key, int value);
  JsonObject& add(std::string_view key, bool value);
  JsonObject& add(std::string_view key, std::string_view value);
  JsonObject& add(std::string_view key, const char* value) { return add(key, std::string_view(value)); }
  JsonObject& add(std::string_view key, const std::optional<double>& value);
  JsonObject& add(std::string_view key, const std::vector<std::string>& values);  // an array of strings
  JsonObject& add(std::string_view key, const std::vector<double>& values);       // an array of numbers
  JsonObject& add(std::string_view key, const JsonObject& value);
  JsonObject& add_null(std::string_view key);
  /// Appends the other object's members, in their order.
  JsonObject& merge(const JsonObject& other);

  /// Pretty-printed with two-space indentation and a trailing newline at the top level.
  std::string dump(int indent = 0) const;
  /// The same content for people: "key: value" lines, nested objects indented, strings unquoted.
  std::string text(int indent = 0) const;

 private:
  struct Member {
    std::string key;
    std::string encoded;                  // a JSON scalar, when `object` is null
    std::string plain;                    // the scalar as text() prints it
    std::shared_ptr<const JsonObject> object;
  };
  JsonObject& add_scalar(std::string_view key, std::string encoded, std::string plain);
  std::vector<Member> members_;
};

std::string json_number(double value);
std::string json_string(std::string_view text);

}  // namespace slam2d::cli
