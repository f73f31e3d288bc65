// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Errors for user input (always on) and debug-only invariant checks.

#include <cassert>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace slam2d {

/// Any error caused by the user's input or environment: bad arguments, unreadable files.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An error in an input file. what() reads "PATH:LINE: message" (line 0 means the whole file).
class ParseError : public Error {
 public:
  ParseError(std::string path, std::size_t line, const std::string& message);
  const std::string& path() const { return path_; }
  std::size_t line() const { return line_; }
  const std::string& message() const { return message_; }

 private:
  std::string path_;
  std::size_t line_;
  std::string message_;
};

/// Throws Error(message) unless `condition` holds. For checks on user input.
inline void check(bool condition, const std::string& message) {
  if (!condition) throw Error(message);
}
/// The same for a literal message: builds no string unless the check fails (for hot paths).
inline void check(bool condition, const char* message) {
  if (!condition) throw Error(message);
}

}  // namespace slam2d

/// Debug-only check of an internal invariant.
#define SLAM2D_ASSERT(condition) assert(condition)
