// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

#include "slam2d/core/error.hpp"

namespace slam2d {

namespace {

std::string make_temp_path(const std::string& path) {
  std::string pattern = path + ".tmp.XXXXXX";
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  const int fd = mkstemp(buffer.data());
  if (fd < 0) throw Error(path + ": cannot create: " + std::strerror(errno));
  // mkstemp makes the file private; give it the permissions a plain create would.
  const mode_t mask = umask(0);
  umask(mask);
  fchmod(fd, 0666 & ~mask);
  close(fd);
  return std::string(buffer.data());
}

void gzip_file(const std::string& from, const std::string& to, const std::string& target) {
  std::FILE* in = std::fopen(from.c_str(), "rb");
  if (in == nullptr) throw Error(target + ": cannot reopen temporary file: " + std::strerror(errno));
  gzFile out = gzopen(to.c_str(), "wb6");
  if (out == nullptr) {
    std::fclose(in);
    throw Error(target + ": cannot write: " + std::strerror(errno));
  }
  char buffer[1 << 16];
  bool ok = true;
  std::size_t n;
  while (ok && (n = std::fread(buffer, 1, sizeof(buffer), in)) > 0) {
    ok = gzwrite(out, buffer, static_cast<unsigned>(n)) == static_cast<int>(n);
  }
  ok = ok && !std::ferror(in);
  std::fclose(in);
  ok = (gzclose(out) == Z_OK) && ok;
  if (!ok) throw Error(target + ": write error while compressing");
}

}  // namespace

void sync_to_disk(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(path + ": cannot open to sync: " + std::strerror(errno));
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  // A file system that cannot sync a directory (EINVAL) gives no stronger promise to keep.
  if (result != 0 && error != EINVAL) throw Error(path + ": cannot sync to disk: " + std::strerror(error));
}

void rename_durably(const std::string& from, const std::string& to) {
  sync_to_disk(from);
  if (std::rename(from.c_str(), to.c_str()) != 0) {
    throw Error(to + ": cannot rename temporary file: " + std::strerror(errno));
  }
  const std::filesystem::path parent = std::filesystem::path(to).parent_path();
  sync_to_disk(parent.empty() ? std::string(".") : parent.string());
}

bool has_gzip_extension(std::string_view path) { return path.size() > 3 && path.ends_with(".gz"); }

AtomicFile::AtomicFile(std::string path, bool gzip)
    : path_(std::move(path)), temp_path_(make_temp_path(path_)), gzip_(gzip) {
  stream_.open(temp_path_, std::ios::binary | std::ios::trunc);
  if (!stream_) {
    std::remove(temp_path_.c_str());
    throw Error(path_ + ": cannot write: " + std::strerror(errno));
  }
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    stream_.close();
    std::remove(temp_path_.c_str());
  }
}

void AtomicFile::commit() {
  stream_.flush();
  const bool ok = static_cast<bool>(stream_);
  stream_.close();
  if (!ok) throw Error(path_ + ": write error");
  std::string final_temp = temp_path_;
  if (gzip_) {
    final_temp = make_temp_path(path_);
    try {
      gzip_file(temp_path_, final_temp, path_);
    } catch (...) {
      std::remove(final_temp.c_str());
      throw;
    }
    std::remove(temp_path_.c_str());
    temp_path_ = final_temp;
  }
  rename_durably(final_temp, path_);
  committed_ = true;
}

void write_file_atomically(const std::string& path, std::string_view content) {
  AtomicFile file(path);
  file.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
  file.commit();
}

void write_file_atomically(const std::string& path, std::span<const std::uint8_t> bytes) {
  write_file_atomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace slam2d
