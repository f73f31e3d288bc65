#pragma once
// Numbers in text files: written in the shortest form that reads back to the same double
// (std::to_chars), and read strictly (std::from_chars): a token must be a number and nothing else.
// Also the small helpers every line-based reader needs (fields, comments, named-field parsing
// that fails with ParseError "PATH:LINE: message").

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace slam2d {

class LineReader;

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
