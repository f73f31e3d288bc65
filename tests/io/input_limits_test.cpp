// SPDX-License-Identifier: BSD-3-Clause
// The bounds on what an input may make slam2d allocate (io/input_limits.hpp): the override text
// is read through the field table and refused when wrong; a declared decompressed size past the
// limits is refused before anything is allocated; and through the CLI with SLAM2D_LIMITS, each
// limit stops a file that crosses it with an error naming the file, the limit and how to raise it.

#include <gtest/gtest.h>

#include <zlib.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/io/detail/compression.hpp"
#include "slam2d/io/input_limits.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::run_command;

TEST(InputLimits, TheOverrideTextIsReadByTheFieldTable) {
  const InputLimits limits = parse_input_limits("max_beams=10, max_line_bytes=100");
  EXPECT_EQ(limits.max_beams, 10u);
  EXPECT_EQ(limits.max_line_bytes, 100u);
  EXPECT_EQ(limits.max_map_cells, InputLimits{}.max_map_cells);
  EXPECT_EQ(parse_input_limits("").max_beams, InputLimits{}.max_beams);
  for (const char* bad : {"max_beam=10", "max_beams=-1", "max_beams=ten", "max_beams", "max_beams=0"}) {
    try {
      parse_input_limits(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find("SLAM2D_LIMITS"), std::string::npos) << error.what();
    }
  }
}

TEST(InputLimits, ADeclaredSizePastTheLimitsIsRefusedBeforeAnyAllocation) {
  const std::vector<std::uint8_t> data(64, 0);
  const std::vector<std::uint8_t> zeros(1 << 20, 0);
  const std::vector<std::uint8_t> packed = detail::compress(detail::Codec::kZstd, zeros);
  // 1 MiB of zeros packs into far less than 1/1000 of it: the ratio refuses a real bomb too.
  EXPECT_THROW(detail::decompress(detail::Codec::kZstd, packed, zeros.size()), Error);
  EXPECT_THROW(detail::decompress(detail::Codec::kBz2, data, std::size_t{1} << 40), Error);  // 1 TiB declared
  EXPECT_THROW(detail::decompress(detail::Codec::kLz4Frame, data, std::size_t{1} << 31), Error);
  const std::vector<std::uint8_t> text(4096, 'a');
  EXPECT_EQ(detail::decompress(detail::Codec::kLz4Frame, detail::compress(detail::Codec::kLz4Frame, text), text.size()),
            text);
}

std::string slam2d_with_limits(const std::string& limits, const std::string& arguments) {
  return "SLAM2D_LIMITS='" + limits + "' " + test::cli_command(arguments);
}

TEST(InputLimits, EachLimitStopsAFileThatCrossesIt) {
  TempDir dir;
  // A gzip bomb: 4 MiB of one line compressed to a few kilobytes.
  const std::string bomb = dir.file("bomb.clf.gz");
  {
    gzFile out = gzopen(bomb.c_str(), "wb9");
    const std::string block(1 << 16, 'a');
    for (int i = 0; i < 64; ++i) gzwrite(out, block.data(), static_cast<unsigned>(block.size()));
    gzclose(out);
  }
  CommandResult result = run_command(slam2d_with_limits("max_line_bytes=1048576", "info " + bomb));
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.errors.find(bomb + ":1: a line longer than 1048576 bytes"), std::string::npos) << result.errors;
  EXPECT_NE(result.errors.find("SLAM2D_LIMITS=max_line_bytes="), std::string::npos) << result.errors;

  std::string flaser = "FLASER 180";
  for (int i = 0; i < 180; ++i) flaser += " 1.0";
  flaser += " 0 0 0 0 0 0 1.0 host 1.0\n";
  const std::string log = dir.file("scan.clf");
  std::ofstream(log) << flaser;
  result = run_command(slam2d_with_limits("max_beams=100", "info " + log));
  EXPECT_NE(result.errors.find(log + ":1: FLASER: num_readings 180 is over max_beams (100"), std::string::npos) << result.errors;
  EXPECT_EQ(run_command(test::cli_command("info " + log)).exit_code, 0) << "within the default";

  std::string graph;
  for (int i = 0; i < 20; ++i) graph += "VERTEX_SE2 " + std::to_string(i) + " 0 0 0\n";
  const std::string g2o = dir.file("graph.g2o");
  std::ofstream(g2o) << graph;
  result = run_command(slam2d_with_limits("max_graph_elements=10", "info " + g2o));
  EXPECT_NE(result.errors.find(g2o + ":11: more than 10 vertices and edges"), std::string::npos) << result.errors;

  result = run_command(slam2d_with_limits("max_bogus=1", "info " + log));
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.errors.find("SLAM2D_LIMITS"), std::string::npos) << result.errors;
}

}  // namespace
}  // namespace slam2d
