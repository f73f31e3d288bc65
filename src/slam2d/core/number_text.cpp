// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/number_text.hpp"

#include <array>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <system_error>

namespace slam2d {

namespace {

// Drops one leading '+' when a digit or '.' follows (std::from_chars does not take '+').
std::string_view strip_plus(std::string_view token) {
  if (token.size() >= 2 && token[0] == '+' && (std::isdigit(static_cast<unsigned char>(token[1])) || token[1] == '.')) {
    token.remove_prefix(1);
  }
  return token;
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

}  // namespace slam2d
