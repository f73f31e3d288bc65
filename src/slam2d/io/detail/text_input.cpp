// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/detail/text_input.hpp"


#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "slam2d/core/error.hpp"
#include "slam2d/io/input_limits.hpp"

namespace slam2d {

LineReader::LineReader(std::string path) : path_(std::move(path)) {
  errno = 0;
  gzFile file = gzopen(path_.c_str(), "rb");
  if (file == nullptr) {
    throw Error(path_ + ": cannot open: " + (errno != 0 ? std::strerror(errno) : "out of memory"));
  }
  gzbuffer(file, 1 << 17);
  file_ = file;
  std::error_code ignored;
  const auto size = std::filesystem::file_size(path_, ignored);
  file_size_ = ignored ? 0.0 : static_cast<double>(size);
}

double LineReader::progress() const {
  if (file_size_ <= 0.0) return 0.0;
  const auto offset = gzoffset(static_cast<gzFile>(file_));
  return std::clamp(static_cast<double>(offset) / file_size_, 0.0, 1.0);
}

LineReader::~LineReader() {
  if (file_ != nullptr) gzclose(static_cast<gzFile>(file_));
}

bool LineReader::next(std::string& line) {
  line.clear();
  auto* file = static_cast<gzFile>(file_);
  char buffer[8192];
  bool read_any = false;
  while (gzgets(file, buffer, sizeof(buffer)) != nullptr) {
    read_any = true;
    const std::size_t n = std::strlen(buffer);
    if (n > 0 && buffer[n - 1] == '\n') {
      line.append(buffer, n - 1);
      break;
    }
    line.append(buffer, n);
    if (line.size() > input_limits().max_line_bytes) {
      ++line_number_;
      fail("a line longer than " + std::to_string(input_limits().max_line_bytes) + " bytes (max_line_bytes; " +
           limit_hint("max_line_bytes") + ")");
    }
  }
  int error = Z_OK;
  const char* message = gzerror(file, &error);
  if (error != Z_OK && error != Z_STREAM_END) {
    ++line_number_;
    fail(std::string("read error: ") + (error == Z_ERRNO ? std::strerror(errno) : message));
  }
  if (!read_any) return false;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  ++line_number_;
  return true;
}

void LineReader::fail(const std::string& message) const { throw ParseError(path_, line_number_, message); }

}  // namespace slam2d
