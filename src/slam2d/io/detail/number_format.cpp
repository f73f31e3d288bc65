// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/detail/number_format.hpp"

#include <cmath>

#include "slam2d/io/detail/text_input.hpp"

namespace slam2d {

namespace {

constexpr std::string_view kFieldSeparators = " \t\r\v\f";

std::string quoted(std::string_view token) {
  std::string text;
  text.reserve(token.size() + 2);
  text.append(1, '\'').append(token).append(1, '\'');
  return text;
}

}  // namespace

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  split_fields(line, fields);
  return fields;
}

void split_fields(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = line.find_first_not_of(kFieldSeparators);
  while (start != std::string_view::npos) {
    const std::size_t stop = line.find_first_of(kFieldSeparators, start);
    fields.push_back(line.substr(start, stop == std::string_view::npos ? std::string_view::npos : stop - start));
    start = stop == std::string_view::npos ? stop : line.find_first_not_of(kFieldSeparators, stop);
  }
}

bool is_blank_or_comment(std::string_view line) {
  const std::size_t first = line.find_first_not_of(kFieldSeparators);
  return first == std::string_view::npos || line[first] == '#';
}

double parse_finite_field(const LineReader& reader, std::string_view token, std::string_view name) {
  const std::optional<double> value = parse_double(token);
  if (!value) reader.fail(std::string(name) + " is not a number: " + quoted(token));
  if (std::isnan(*value)) reader.fail("NaN in " + std::string(name));
  if (std::isinf(*value)) reader.fail(std::string(name) + " is infinite or out of range: " + quoted(token));
  return *value;
}

int parse_int_field(const LineReader& reader, std::string_view token, std::string_view name) {
  const std::optional<int> value = parse_int(token);
  if (!value) reader.fail(std::string(name) + " is not an integer: " + quoted(token));
  return *value;
}

}  // namespace slam2d
