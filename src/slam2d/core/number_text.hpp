// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Numbers as text: written in the shortest form that reads back to the same double
// (std::to_chars), and read strictly (std::from_chars): a token must be a number and nothing
// else. io/number_format.hpp builds the line readers' field parsing on these.

#include <optional>
#include <string>
#include <string_view>

namespace slam2d {

/// Shortest exact decimal form of `value` ("0.1", "1e+300", "-0"; "nan"/"inf" if not finite).
std::string format_number(double value);
/// Appends format_number(value) to `out` without a temporary string.
void append_number(std::string& out, double value);

/// The double spelled by the whole of `token`, or nullopt when it is not a number or has trailing
/// characters. Accepts one leading '+'. "nan" and "inf" parse (the caller decides whether they are
/// allowed); overflow gives +-inf, underflow the nearest subnormal or zero.
std::optional<double> parse_double(std::string_view token);
/// The int spelled by the whole of `token` (decimal, optional '-' or '+'), else nullopt.
std::optional<int> parse_int(std::string_view token);

}  // namespace slam2d
