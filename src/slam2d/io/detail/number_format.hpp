// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Numbers in text files: format_number and the strict parse_double / parse_int of
// core/number_text.hpp (included here), and the small helpers every line-based reader needs
// (fields, comments, named-field parsing that fails with ParseError "PATH:LINE: message").

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "slam2d/core/number_text.hpp"

namespace slam2d {

class LineReader;

/// Splits `line` at white space (space, tab, CR, VT, FF), dropping empty fields. The views point into `line`.
std::vector<std::string_view> split_fields(std::string_view line);
/// The same into a caller's vector (cleared first), so a reader can reuse it line after line.
void split_fields(std::string_view line, std::vector<std::string_view>& fields);
/// True for lines that are empty, all white space, or whose first non-blank character is '#'.
bool is_blank_or_comment(std::string_view line);

/// Parses a finite number for the field called `name`, else reader.fail() with
/// "NAME is not a number: 'TOKEN'", "NaN in NAME" or "NAME is infinite or out of range: 'TOKEN'".
double parse_finite_field(const LineReader& reader, std::string_view token, std::string_view name);
/// Parses an int for the field called `name`, else reader.fail() with "NAME is not an integer: 'TOKEN'".
int parse_int_field(const LineReader& reader, std::string_view token, std::string_view name);

}  // namespace slam2d
