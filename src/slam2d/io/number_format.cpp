#include "slam2d/io/number_format.hpp"

#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <system_error>

#include "slam2d/io/text_input.hpp"

namespace slam2d {

namespace {

constexpr std::string_view kFieldSeparators = " \t\r\v\f";

// Drops one leading '+' when a digit or '.' follows (std::from_chars does not take '+').
std::string_view strip_plus(std::string_view token) {
  if (token.size() >= 2 && token[0] == '+' && (std::isdigit(static_cast<unsigned char>(token[1])) || token[1] == '.')) {
    token.remove_prefix(1);
  }
  return token;
}

std::string quoted(std::string_view token) {
  std::string text;
  text.reserve(token.size() + 2);
  text.append(1, '\'').append(token).append(1, '\'');
  return text;
}

}  // namespace

void append_number(std::string& out, double value) {
  std::array<char, 32> buffer;  // the shortest form of a double is at most 24 characters
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  out.append(buffer.data(), result.ptr);
}

std::string format_number(double value) {
  std::string out;
  append_number(out, value);
  return out;
}

std::optional<double> parse_double(std::string_view token) {
  token = strip_plus(token);
  if (token.empty()) return std::nullopt;
  double value = 0.0;
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, value);
  if (result.ptr != end) return std::nullopt;
  if (result.ec == std::errc::result_out_of_range) {
    // from_chars leaves the value unset on overflow and underflow; strtod gives the nearest
    // double (+-inf or a subnormal or zero).
    const std::string copy(token);
    return std::strtod(copy.c_str(), nullptr);
  }
  if (result.ec != std::errc()) return std::nullopt;
  return value;
}

std::optional<int> parse_int(std::string_view token) {
  if (token.size() >= 2 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  int value = 0;
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, value);
  if (token.empty() || result.ec != std::errc() || result.ptr != end) return std::nullopt;
  return value;
}

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
