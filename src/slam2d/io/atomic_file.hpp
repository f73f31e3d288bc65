// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Atomic output: everything is written to a temporary file beside the target and renamed over
// it on commit(), so a failed run never leaves a half-written file. The file is synced to disk
// before the rename and its folder after it, so that a crash or a power cut at any moment leaves
// the previous file or the new one, never an empty or partial one (ext4's delayed allocation
// otherwise may commit the rename before the data).

#include <cstdint>
#include <fstream>
#include <span>
#include <string>
#include <string_view>

namespace slam2d {

class AtomicFile {
 public:
  /// Opens a temporary file beside `path`. With `gzip`, commit() stores the content compressed.
  /// Throws Error naming the path if it cannot be created.
  explicit AtomicFile(std::string path, bool gzip = false);
  ~AtomicFile();  // removes the temporary file unless committed
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ostream& stream() { return stream_; }
  /// Flushes, checks for write errors and renames the temporary file to the target.
  void commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string temp_path_;
  bool gzip_;
  bool committed_ = false;
  std::ofstream stream_;
};

/// fsync of a file or a folder; Error naming it when that fails.
void sync_to_disk(const std::string& path);
/// Renames `from` (a finished file or folder) to `to` so that it survives a crash: `from` is
/// synced first, the folder holding `to` after.
void rename_durably(const std::string& from, const std::string& to);

/// True when the path ends in ".gz".
bool has_gzip_extension(std::string_view path);

void write_file_atomically(const std::string& path, std::string_view content);
void write_file_atomically(const std::string& path, std::span<const std::uint8_t> bytes);

}  // namespace slam2d
