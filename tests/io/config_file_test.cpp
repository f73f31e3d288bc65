// SPDX-License-Identifier: BSD-3-Clause
// ConfigNode: typed reads, errors naming file and line, misspelt keys rejected.

#include "slam2d/io/config_file.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "support/test_support.hpp"

namespace slam2d {
namespace {

enum class Mode { kFast, kExact };

constexpr const char* kYaml =
    "matcher: pl-icp\n"
    "max_iterations: 40\n"
    "epsilon: 1.0e-4\n"
    "trim: true\n"
    "mode: exact\n"
    "filters:\n"
    "  - {kind: voxel, size: 0.05}\n"
    "  - {kind: range_clip, max: 25}\n";

TEST(ConfigNode, ReadsTypedValuesAndLists) {
  const ConfigNode root = ConfigNode::parse(kYaml, "test.yaml");
  std::string matcher;
  int iterations = 0;
  double epsilon = 0.0;
  bool trim = false;
  Mode mode = Mode::kFast;
  double untouched = 7.0;
  EXPECT_TRUE(root.read("matcher", matcher));
  EXPECT_TRUE(root.read("max_iterations", iterations));
  EXPECT_TRUE(root.read("epsilon", epsilon));
  EXPECT_TRUE(root.read("trim", trim));
  EXPECT_TRUE(root.read_enum("mode", mode, {{"fast", Mode::kFast}, {"exact", Mode::kExact}}));
  EXPECT_FALSE(root.read("absent", untouched));
  EXPECT_EQ(matcher, "pl-icp");
  EXPECT_EQ(iterations, 40);
  EXPECT_DOUBLE_EQ(epsilon, 1e-4);
  EXPECT_TRUE(trim);
  EXPECT_EQ(mode, Mode::kExact);
  EXPECT_DOUBLE_EQ(untouched, 7.0);
  const std::vector<ConfigNode> filters = root.at("filters").items();
  ASSERT_EQ(filters.size(), 2U);
  EXPECT_EQ(filters[1].at("kind").as_string(), "range_clip");
  EXPECT_DOUBLE_EQ(filters[1].at("max").as_double(), 25.0);
  EXPECT_EQ(filters[1].line(), 8U);
  EXPECT_NO_THROW(root.reject_unread_keys());
}

TEST(ConfigNode, ErrorsNameTheFileAndLine) {
  const ConfigNode root = ConfigNode::parse(kYaml, "test.yaml");
  int value = 0;
  try {
    root.read("epsilon", value);  // 1.0e-4 is not an integer
    FAIL() << "expected a ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.path(), "test.yaml");
    EXPECT_EQ(e.line(), 3U);
  }
  Mode mode = Mode::kFast;
  EXPECT_THROW(ConfigNode::parse("mode: quick\n", "m.yaml").read_enum("mode", mode, {{"fast", Mode::kFast}}), ParseError);
  EXPECT_THROW(ConfigNode::parse("x: .nan\n", "n.yaml").at("x").as_double(), ParseError);
  EXPECT_THROW(ConfigNode::parse("a: [1, 2\n", "broken.yaml"), ParseError);
  EXPECT_THROW(ConfigNode::parse("- 1\n- 2\n", "list.yaml"), ParseError);
  EXPECT_THROW(ConfigNode::parse("a: 1\n", "a.yaml").at("b"), ParseError);
  std::uint64_t seed = 0;
  EXPECT_THROW(ConfigNode::parse("seed: -3\n", "s.yaml").read("seed", seed), ParseError);
}

TEST(ConfigNode, UnreadKeyIsRejectedWithItsLine) {
  const ConfigNode root = ConfigNode::parse("max_iterations: 5\nmax_itrations: 6\n", "typo.yaml");
  int iterations = 0;
  root.read("max_iterations", iterations);
  try {
    root.reject_unread_keys();
    FAIL() << "expected a ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 2U);
    EXPECT_NE(std::string(e.what()).find("max_itrations"), std::string::npos);
  }
}

TEST(ConfigNode, LoadsFilesAndReportsMissingOnes) {
  const test::TempDir dir;
  const std::string path = dir.file("c.yaml");
  std::ofstream(path) << "a: 1\n";
  EXPECT_EQ(ConfigNode::load(path).at("a").as_integer(), 1);
  EXPECT_THROW(ConfigNode::load(dir.file("missing.yaml")), Error);
}

TEST(ConfigFile, UnsignedIntegersReadTheirWholeRange) {
  const ConfigNode node = ConfigNode::parse("big: 18446744073709551615\nsmall: 7\nnegative: -1\nover: 18446744073709551616\n");
  std::uint64_t value = 0;
  ASSERT_TRUE(node.read("big", value));
  EXPECT_EQ(value, 18446744073709551615ULL);
  ASSERT_TRUE(node.read("small", value));
  EXPECT_EQ(value, 7u);
  EXPECT_THROW(node.read("negative", value), ParseError);
  EXPECT_THROW(node.read("over", value), ParseError);
}

}  // namespace
}  // namespace slam2d
