// SPDX-License-Identifier: BSD-3-Clause
// The fuzz targets (fuzz/targets.hpp) in the ordinary test build: every input a fuzzing run once
// crashed on (tests/fixtures/fuzz/TARGET/) is refused or read with nothing else escaping, and so is
// a fixed set of hostile inputs for every target (empty, truncated headers, random bytes, huge
// counts). Under `make check-sanitizers` the same inputs run with ASan and UBSan.

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "targets.hpp"

namespace slam2d {
namespace {

std::vector<std::uint8_t> bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Inputs that every parser must refuse cleanly whatever it expects.
std::vector<std::vector<std::uint8_t>> hostile_inputs() {
  std::vector<std::vector<std::uint8_t>> inputs{
      {},
      bytes_of("\n"),
      bytes_of("#ROSBAG V2.0\n"),
      bytes_of(std::string("\x89MCAP0\r\n", 8)),
      bytes_of(std::string("\x89MCAP0\r\n\x01\xff\xff\xff\xff\xff\xff\xff\x7f", 17)),  // a record claiming 2^63 bytes
      bytes_of("FLASER 4294967295 1 2 3\n"),
      bytes_of("FLASER 180" + std::string(180, ' ') + "\n"),
      bytes_of("ROBOTLASER1 0 -1.57 3.14 0.01 81.9 0.01 0 1000000000000 1 2\n"),
      bytes_of("VERTEX_SE2 18446744073709551615 0 0 0\nEDGE_SE2 0 18446744073709551615 1 0 0 1 0 0 1 0 1\n"),
      bytes_of("P5\n100000 100000\n255\n"),
      bytes_of("image: map.pgm\nresolution: 1e-300\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.2\n"),
      bytes_of("a: &a [*a, *a]\nb: *a\n"),
      bytes_of("SQLite format 3"),
      bytes_of(std::string("\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03", 10)),  // a gzip header, then nothing
  };
  std::uint64_t state = 11;
  for (int n : {1, 7, 64, 4096}) {
    std::vector<std::uint8_t> random;
    for (int i = 0; i < n; ++i) {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      random.push_back(static_cast<std::uint8_t>(state >> 56));
    }
    inputs.push_back(random);
  }
  return inputs;
}

TEST(FuzzTargets, HostileInputsAreRefusedCleanlyByEveryTarget) {
  for (const fuzz::NamedTarget& target : fuzz::targets()) {
    for (const auto& input : hostile_inputs()) {
      EXPECT_NO_THROW(target.run(input.data(), input.size())) << target.name << ", " << input.size() << " bytes";
    }
  }
}

TEST(FuzzTargets, EverySavedFindingStaysFixed) {
  const std::filesystem::path root = test::fixture_path("fuzz");
  std::size_t inputs = 0;
  for (const fuzz::NamedTarget& target : fuzz::targets()) {
    const std::filesystem::path dir = root / target.name;
    if (!std::filesystem::is_directory(dir)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      const std::vector<std::uint8_t> input = read_bytes(entry.path());
      EXPECT_NO_THROW(target.run(input.data(), input.size())) << entry.path();
      ++inputs;
    }
  }
  RecordProperty("inputs", static_cast<int>(inputs));
}

TEST(FuzzTargets, UnknownTargetIsRefused) { EXPECT_THROW(fuzz::target("nothing"), std::invalid_argument); }

}  // namespace
}  // namespace slam2d
