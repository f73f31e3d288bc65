// SPDX-License-Identifier: BSD-3-Clause
// Relations files (Kuemmerle et al. 2009): hand-computed parse, exact round trips, malformed input.
#include "slam2d/io/relations.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::fixture_path;
using test::TempDir;
using test::expect_parse_error;

void expect_same(const std::vector<Relation>& actual, const std::vector<Relation>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].stamp_from, expected[i].stamp_from) << i;
    EXPECT_EQ(actual[i].stamp_to, expected[i].stamp_to) << i;
    EXPECT_EQ(actual[i].T_from_to.x(), expected[i].T_from_to.x()) << i;
    EXPECT_EQ(actual[i].T_from_to.y(), expected[i].T_from_to.y()) << i;
    EXPECT_EQ(actual[i].T_from_to.theta(), expected[i].T_from_to.theta()) << i;
  }
}

TEST(Relations, ReadsHandWrittenFixture) {
  const auto relations = read_relations(fixture_path("relations/good.relations"));
  ASSERT_EQ(relations.size(), 3u);
  EXPECT_EQ(relations[0].stamp_from, 100.5);
  EXPECT_EQ(relations[0].stamp_to, 101.25);
  EXPECT_EQ(relations[0].T_from_to.x(), 1.5);
  EXPECT_EQ(relations[0].T_from_to.y(), -0.25);
  EXPECT_EQ(relations[0].T_from_to.theta(), 0.5);
  EXPECT_EQ(relations[0].line, 3u);  // after a comment and a blank line
  // Tab-separated, with z/roll/pitch present (ignored) and yaw the SE2 angle.
  EXPECT_EQ(relations[1].stamp_to, 102.0);
  EXPECT_EQ(relations[1].T_from_to.x(), -0.03);
  EXPECT_EQ(relations[1].T_from_to.y(), 2.0);
  EXPECT_EQ(relations[1].T_from_to.theta(), -3.0);
  EXPECT_EQ(relations[1].line, 4u);
  // yaw 3.5 rad is wrapped to [-pi, pi); stamps going backwards are kept.
  EXPECT_DOUBLE_EQ(relations[2].T_from_to.theta(), 3.5 - 2.0 * std::numbers::pi);
  EXPECT_EQ(relations[2].stamp_from, 102.0);
  EXPECT_EQ(relations[2].stamp_to, 100.5);
  EXPECT_EQ(relations[2].line, 6u);
}

std::vector<Relation> random_relations(std::size_t n) {
  Rng rng(7);
  std::vector<Relation> relations;
  double stamp = 976052896.784509;
  for (std::size_t i = 0; i < n; ++i) {
    const double dt = rng.uniform(0.0, 10.0);
    relations.push_back({.stamp_from = stamp,
                         .stamp_to = stamp + dt,
                         .T_from_to = SE2(rng.uniform(-50.0, 50.0), rng.gaussian(0.0, 1e-7), rng.uniform(-4.0, 4.0)),
                         .line = 0});
    stamp += dt / 3.0;
  }
  relations.push_back({.stamp_from = 0.1, .stamp_to = 1e-300, .T_from_to = SE2(1.0 / 3.0, -0.0, -std::numbers::pi), .line = 0});
  return relations;
}

TEST(Relations, WriteThenReadIsExact) {
  TempDir dir;
  const auto relations = random_relations(200);
  for (const std::string name : {"out.relations", "out.relations.gz"}) {
    write_relations(dir.file(name), relations);
    const auto back = read_relations(dir.file(name));
    expect_same(back, relations);
    EXPECT_EQ(back[5].line, 6u);
  }
  // The .gz file really is gzip (magic bytes 1f 8b).
  std::ifstream gz(dir.file("out.relations.gz"), std::ios::binary);
  EXPECT_EQ(gz.get(), 0x1f);
  EXPECT_EQ(gz.get(), 0x8b);
}

TEST(Relations, WritesEightColumnsWithZeroZRollPitch) {
  TempDir dir;
  write_relations(dir.file("one.relations"), {{.stamp_from = 1.5, .stamp_to = 2.0, .T_from_to = SE2(0.1, -2.0, 0.25), .line = 0}});
  std::ifstream in(dir.file("one.relations"));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "1.5 2 0.1 -2 0 0 0 0.25");
}

TEST(Relations, MalformedLinesGiveParseErrorWithPathAndLine) {
  expect_parse_error(read_relations, fixture_path("relations/short_line.relations"), 3, "expected 8 numbers");
  expect_parse_error(read_relations, fixture_path("relations/short_line.relations"), 3, "got 5");
  expect_parse_error(read_relations, fixture_path("relations/bad_number.relations"), 2, "x is not a number: 'abc'");
  expect_parse_error(read_relations, fixture_path("relations/nan_yaw.relations"), 3, "NaN in yaw");
  expect_parse_error(read_relations, fixture_path("relations/trailing_garbage.relations"), 1,
                     "yaw is not a number: '0.5x'");
}

TEST(Relations, MissingFileGivesErrorNamingThePath) {
  const std::string path = fixture_path("relations/no_such_file.relations");
  try {
    read_relations(path);
    FAIL() << "no Error";
  } catch (const ParseError&) {
    FAIL() << "a missing file is not a parse error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(Relations, WriterRefusesNonFiniteValuesAndLeavesNoFile) {
  TempDir dir;
  const std::string path = dir.file("bad.relations");
  EXPECT_THROW(write_relations(path, {{.stamp_from = std::nan(""), .stamp_to = 1.0, .T_from_to = SE2(), .line = 0}}), Error);
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace slam2d
