// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared helpers for the slam2d tests.

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d::test {

/// Path of a file in tests/fixtures.
std::string fixture_path(const std::string& name);

/// A fresh, empty temporary directory, removed when the object goes away.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

/// $SLAM2D_DATA if it names a folder, else nullopt.
std::optional<std::filesystem::path> real_data_dir();

/// True when $SLAM2D_REQUIRE_DATA=1 (set by .ci/run): missing data is then a failure, not a skip.
bool real_data_required();

/// A copy of the rosbag2 folder `folder` in `into` (a new subfolder of the same name): metadata.yaml
/// and each storage file, those stored as NAME.gz gunzipped to NAME (zlib). Returns the copy's path.
std::filesystem::path unpack_rosbag2(const std::filesystem::path& folder, const std::filesystem::path& into);

/// The path of the slam2d command-line tool (from $SLAM2D_BIN).
std::string cli_path();
/// A shell command running the slam2d tool with `arguments`.
std::string cli_command(const std::string& arguments);
/// The same, under the name the command-line tests read best: run_command(slam2d("map ...")).
inline std::string slam2d(const std::string& arguments) { return cli_command(arguments); }

/// Runs a shell command, returns its exit status; stdout and stderr are captured.
struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout
  std::string errors;  // stderr
};
CommandResult run_command(const std::string& command);

/// A simulated office log and its ground truth in a folder of their own: `slam2d simulate --quiet
/// --duration DURATION [--seed SEED] --out DIR/NAME --truth DIR/truth.txt`. A failed simulation
/// fails the test that made it.
class SimulatedLog {
 public:
  SimulatedLog(double duration, std::optional<unsigned> seed, const std::string& name = "office.clf");
  const std::string& log() const { return log_; }
  const std::string& truth() const { return truth_; }
  const TempDir& dir() const { return dir_; }

 private:
  TempDir dir_;
  std::string log_;
  std::string truth_;
};

/// The number stored under "key" in a JSON text (first occurrence, any depth); nullopt if absent
/// or not a number. Enough for the flat summaries the CLI prints.
std::optional<double> json_number(const std::string& json, const std::string& key);

/// Number of non-empty, non-comment lines in a text file.
std::size_t count_data_lines(const std::string& path);

/// Checks that read(path) throws ParseError for `path` at `line`, whose what() starts with
/// "PATH:LINE: " and whose message contains `needle`.
template <typename Read>
void expect_parse_error(Read&& read, const std::string& path, std::size_t line, const std::string& needle) {
  try {
    read(path);
    ADD_FAILURE() << "no ParseError for " << path;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_EQ(e.line(), line);
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ":" + std::to_string(line) + ": ", 0), 0u) << what;
    EXPECT_NE(e.message().find(needle), std::string::npos) << what;
  }
}

::testing::AssertionResult poses_near(const SE2& actual, const SE2& expected, double translation_tolerance,
                                      double angle_tolerance);

}  // namespace slam2d::test

/// Skips (or, under SLAM2D_REQUIRE_DATA=1, fails) the test when the real data folder is absent;
/// else binds `dir` to it.
#define SLAM2D_REQUIRE_REAL_DATA(dir)                                                        \
  const auto dir##_optional = ::slam2d::test::real_data_dir();                                \
  if (!dir##_optional) {                                                                     \
    if (::slam2d::test::real_data_required()) FAIL() << "SLAM2D_DATA is not a folder";        \
    GTEST_SKIP() << "real data not found: set SLAM2D_DATA to ../shared/data to run this test"; \
  }                                                                                          \
  const std::filesystem::path dir = *dir##_optional
