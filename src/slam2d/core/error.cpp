// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {
std::string format_location(const std::string& path, std::size_t line, const std::string& message) {
  if (line == 0) return path + ": " + message;
  return path + ":" + std::to_string(line) + ": " + message;
}
}  // namespace

ParseError::ParseError(std::string path, std::size_t line, const std::string& message)
    : Error(format_location(path, line, message)),
      path_(std::move(path)),
      line_(line),
      message_(message) {}

}  // namespace slam2d
