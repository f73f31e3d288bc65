// SPDX-License-Identifier: BSD-3-Clause
// A file that is not a CARMEN log is refused by name (issue 25): a known binary by its magic, any
// other binary at its first control byte, a text file with no CARMEN line in its first 1000 lines
// or at all. A real log with a junk line after its first CARMEN line still reads (the line is
// skipped and counted), and comments before the first message are no reason to refuse.

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/io/carmen.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::TempDir;

std::string write_bytes(const TempDir& dir, const std::string& name, const std::string& bytes) {
  const std::string path = dir.file(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

// Reads the whole log; the error's message when it throws, else "".
std::string read_error(const std::string& path) {
  try {
    CarmenReader reader(path);
    while (reader.next()) {
    }
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

const std::string kFlaser = "FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 1.5 host 1.5\n";

TEST(NotCarmen, AKnownBinaryIsNamed) {
  TempDir dir;
  const std::string elf = write_bytes(dir, "tool", std::string("\x7f" "ELF\x02\x01\x01\0\0\0", 10) + "rest\n");
  EXPECT_EQ(read_error(elf), elf + ":1: not a CARMEN log: it is an ELF executable");
  const std::string db3 = write_bytes(dir, "bag.db3", std::string("SQLite format 3\0", 16) + "\x10\x00\n");
  EXPECT_NE(read_error(db3).find("an SQLite database (a rosbag2 .db3 file: give its folder)"), std::string::npos);
}

TEST(NotCarmen, AnyOtherBinaryIsRefusedAtItsFirstControlByte) {
  TempDir dir;
  std::string bytes;
  std::uint64_t state = 7;
  for (int i = 0; i < 4096; ++i) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    bytes += static_cast<char>(state >> 56);
  }
  const std::string junk = write_bytes(dir, "junk.clf", bytes);
  const std::string error = read_error(junk);
  EXPECT_NE(error.find("not a CARMEN log: binary data (byte 0x"), std::string::npos) << error;
  EXPECT_EQ(error.rfind(junk + ":", 0), 0u) << error;
  // Junk behind a CARMEN type name is binary, not a malformed laser line.
  const std::string disguised = write_bytes(dir, "disguised.clf", std::string("FLASER \x01\x02\x03\n", 11));
  EXPECT_NE(read_error(disguised).find("binary data (byte 0x01)"), std::string::npos) << read_error(disguised);
}

TEST(NotCarmen, TextWithoutACarmenLineIsRefused) {
  TempDir dir;
  std::string csv;
  for (int i = 0; i < 2000; ++i) csv += std::to_string(i) + ",1.0,2.0\n";
  const std::string long_csv = write_bytes(dir, "table.csv", csv);
  EXPECT_EQ(read_error(long_csv),
            long_csv + ":1000: not a CARMEN log: no FLASER, RLASER, ROBOTLASER1, RAWLASER, ODOM, TRUEPOS or PARAM line in "
                       "the first 1000 lines");
  const std::string short_text = write_bytes(dir, "notes.txt", "a note\nanother\n");
  EXPECT_NE(read_error(short_text).find("notes.txt:2: not a CARMEN log: no FLASER"), std::string::npos)
      << read_error(short_text);
}

TEST(NotCarmen, ARealLogWithAJunkLineOrLeadingCommentsStillReads) {
  TempDir dir;
  const std::string after = write_bytes(dir, "after.clf", kFlaser + "GARBAGE \xff\xfe\n" + kFlaser);
  EXPECT_EQ(read_error(after), "");
  CarmenReader reader(after);
  int messages = 0;
  while (reader.next()) ++messages;
  EXPECT_EQ(messages, 2);
  EXPECT_EQ(reader.stats().skipped_lines, 1u);
  std::string comments;
  for (int i = 0; i < 1500; ++i) comments += "# a comment line\n";
  EXPECT_EQ(read_error(write_bytes(dir, "comments.clf", comments + kFlaser)), "");
  EXPECT_EQ(read_error(write_bytes(dir, "empty.clf", "")), "") << "an empty log is empty, not another format";
}

}  // namespace
}  // namespace slam2d
