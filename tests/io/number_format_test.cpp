// SPDX-License-Identifier: BSD-3-Clause
// Shortest exact number formatting and strict token parsing.
#include "slam2d/io/detail/number_format.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "slam2d/core/rng.hpp"

namespace slam2d {
namespace {

TEST(NumberFormat, WritesTheShortestFormThatReadsBackExactly) {
  EXPECT_EQ(format_number(0.1), "0.1");
  EXPECT_EQ(format_number(-2.0), "-2");
  EXPECT_EQ(format_number(976052905.167303), "976052905.167303");
  EXPECT_EQ(format_number(1e300), "1e+300");
  Rng rng(5);
  for (int i = 0; i < 20000; ++i) {
    // Random bit patterns cover every exponent, subnormals included.
    double value;
    const std::uint64_t bits = rng.next_u64();
    std::memcpy(&value, &bits, sizeof value);
    if (!std::isfinite(value)) continue;
    const auto back = parse_double(format_number(value));
    ASSERT_TRUE(back.has_value()) << format_number(value);
    EXPECT_EQ(std::memcmp(&*back, &value, sizeof value), 0) << format_number(value);
  }
}

TEST(NumberFormat, ParsesWholeTokensOnly) {
  EXPECT_EQ(parse_double("1.5"), 1.5);
  EXPECT_EQ(parse_double("+1.5"), 1.5);
  EXPECT_EQ(parse_double("-3e-2"), -0.03);
  EXPECT_EQ(parse_double(".5"), 0.5);
  EXPECT_EQ(parse_double("1e-400"), 0.0);  // underflow: the nearest double
  EXPECT_TRUE(std::isinf(*parse_double("1e400")));
  EXPECT_TRUE(std::isnan(*parse_double("nan")));
  for (const char* bad : {"", "abc", "1.5x", "1,5", "0x10", "+-1", "++1", "1 ", " 1", "-", "."}) {
    EXPECT_FALSE(parse_double(bad).has_value()) << "'" << bad << "'";
  }
  EXPECT_EQ(parse_int("42"), 42);
  EXPECT_EQ(parse_int("-7"), -7);
  EXPECT_EQ(parse_int("+7"), 7);
  for (const char* bad : {"", "1.5", "1e3", "x", "99999999999", "+-1", "+"}) {
    EXPECT_FALSE(parse_int(bad).has_value()) << "'" << bad << "'";
  }
}

TEST(NumberFormat, SplitsFieldsAndSpotsComments) {
  const auto fields = split_fields("\t VERTEX_SE2  1\t2.5 -3 ");
  ASSERT_EQ(fields.size(), 4u);
  EXPECT_EQ(fields[0], "VERTEX_SE2");
  EXPECT_EQ(fields[1], "1");
  EXPECT_EQ(fields[2], "2.5");
  EXPECT_EQ(fields[3], "-3");
  EXPECT_TRUE(split_fields("   ").empty());
  EXPECT_TRUE(is_blank_or_comment(""));
  EXPECT_TRUE(is_blank_or_comment(" \t"));
  EXPECT_TRUE(is_blank_or_comment("  # note"));
  EXPECT_FALSE(is_blank_or_comment("1 2 # note"));
}

}  // namespace
}  // namespace slam2d
