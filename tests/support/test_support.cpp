// SPDX-License-Identifier: BSD-3-Clause
#include "support/test_support.hpp"

#include <sys/wait.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "slam2d/core/angles.hpp"

namespace slam2d::test {

namespace {
std::string env_or_empty(const char* name) {
  const char* value = std::getenv(name);
  return value ? value : "";
}

std::string read_all(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

std::string fixture_path(const std::string& name) {
  // Tests run from the repository root (ctest's working directory); SLAM2D_FIXTURES overrides.
  std::string root = env_or_empty("SLAM2D_FIXTURES");
  if (root.empty()) root = "tests/fixtures";
  return (std::filesystem::path(root) / name).string();
}

TempDir::TempDir() {
  std::random_device device;
  const auto base = std::filesystem::temp_directory_path();
  for (int attempt = 0; attempt < 100; ++attempt) {
    auto candidate = base / ("slam2d-test-" + std::to_string(device()));
    if (std::filesystem::create_directory(candidate)) {
      path_ = candidate;
      return;
    }
  }
  throw std::runtime_error("TempDir: cannot create a temporary directory");
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::filesystem::path unpack_rosbag2(const std::filesystem::path& folder, const std::filesystem::path& into) {
  namespace fs = std::filesystem;
  const fs::path copy = into / folder.filename();
  fs::create_directories(copy);
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const fs::path& from = entry.path();
    if (from.extension() != ".gz") {
      fs::copy_file(from, copy / from.filename(), fs::copy_options::overwrite_existing);
      continue;
    }
    gzFile in = gzopen(from.c_str(), "rb");
    if (!in) throw Error("unpack_rosbag2: cannot open " + from.string());
    std::ofstream out(copy / from.stem(), std::ios::binary);
    char buffer[1 << 16];
    int n;
    while ((n = gzread(in, buffer, sizeof buffer)) > 0) out.write(buffer, n);
    gzclose(in);
    if (n < 0 || !out) throw Error("unpack_rosbag2: cannot gunzip " + from.string());
  }
  return copy;
}

std::optional<std::filesystem::path> real_data_dir() {
  const std::string dir = env_or_empty("SLAM2D_DATA");
  if (dir.empty() || !std::filesystem::is_directory(dir)) return std::nullopt;
  return std::filesystem::path(dir);
}

bool real_data_required() { return env_or_empty("SLAM2D_REQUIRE_DATA") == "1"; }

std::string cli_path() {
  const std::string bin = env_or_empty("SLAM2D_BIN");
  return bin.empty() ? "slam2d" : bin;
}

std::string cli_command(const std::string& arguments) { return "'" + cli_path() + "' " + arguments; }

SimulatedLog::SimulatedLog(double duration, std::optional<unsigned> seed, const std::string& name)
    : log_(dir_.file(name)), truth_(dir_.file("truth.txt")) {
  std::string arguments = "simulate --quiet --duration " + std::to_string(duration) + " --out '" + log_ + "' --truth '" + truth_ + "'";
  if (seed) arguments += " --seed " + std::to_string(*seed);
  const CommandResult result = run_command(cli_command(arguments));
  EXPECT_EQ(result.exit_code, 0) << result.errors;
}

CommandResult run_command(const std::string& command) {
  TempDir dir;
  const auto out = dir.path() / "stdout";
  const auto err = dir.path() / "stderr";
  const std::string full = command + " >'" + out.string() + "' 2>'" + err.string() + "' </dev/null";
  const int status = std::system(full.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.output = read_all(out);
  result.errors = read_all(err);
  return result;
}

std::optional<double> json_number(const std::string& json, const std::string& key) {
  const std::string quoted = "\"" + key + "\":";
  const auto at = json.find(quoted);
  if (at == std::string::npos) return std::nullopt;
  const char* begin = json.c_str() + at + quoted.size();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end == begin) return std::nullopt;
  return value;
}

std::size_t count_data_lines(const std::string& path) {
  std::ifstream in(path);
  std::size_t count = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') ++count;
  }
  return count;
}

::testing::AssertionResult poses_near(const SE2& actual, const SE2& expected, double translation_tolerance,
                                      double angle_tolerance) {
  const double dt = (actual.translation() - expected.translation()).norm();
  const double da = std::abs(angle_difference(actual.theta(), expected.theta()));
  if (dt <= translation_tolerance && da <= angle_tolerance) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "pose " << actual << " differs from " << expected << " by " << dt
                                       << " m and " << da << " rad (tolerances " << translation_tolerance
                                       << " m, " << angle_tolerance << " rad)";
}

}  // namespace slam2d::test
