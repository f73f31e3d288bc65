// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Line-by-line reading of plain or gzip-compressed text files, streamed (zlib reads both).

#include <cstddef>
#include <string>

namespace slam2d {

class LineReader {
 public:
  /// Opens `path`; throws Error("PATH: cannot open: reason") if it cannot be read.
  explicit LineReader(std::string path);
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  /// Reads the next line (without its line ending) into `line`; false at the end of the file.
  /// Throws ParseError on a read or decompression error.
  bool next(std::string& line);
  /// 1-based number of the line last returned by next().
  std::size_t line_number() const { return line_number_; }
  const std::string& path() const { return path_; }
  /// Fraction of the file (as stored on disk, compressed or not) consumed so far, in [0, 1].
  double progress() const;
  /// Throws ParseError(path, current line, message).
  [[noreturn]] void fail(const std::string& message) const;

 private:
  std::string path_;
  void* file_ = nullptr;  // gzFile
  std::size_t line_number_ = 0;
  double file_size_ = 0.0;  // bytes on disk
};

}  // namespace slam2d
