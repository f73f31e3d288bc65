// SPDX-License-Identifier: BSD-3-Clause
// Tests of the ROS map_server format reader/writer (src/slam2d/io/map_io.cpp).

#include "slam2d/io/map_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "slam2d/core/error.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::fixture_path;
using test::TempDir;

/// Field-by-field equality (OccupancyMap's defaulted operator== is deleted: SE2 has no ==).
::testing::AssertionResult same_map(const OccupancyMap& a, const OccupancyMap& b) {
  if (a.width != b.width || a.height != b.height) {
    return ::testing::AssertionFailure() << "size " << a.width << "x" << a.height << " vs " << b.width << "x" << b.height;
  }
  if (a.resolution != b.resolution) return ::testing::AssertionFailure() << "resolution " << a.resolution << " vs " << b.resolution;
  if (a.origin.vector() != b.origin.vector()) {
    return ::testing::AssertionFailure() << "origin " << a.origin << " vs " << b.origin;
  }
  if (a.cells != b.cells) return ::testing::AssertionFailure() << "cells differ";
  return ::testing::AssertionSuccess();
}

std::string map_fixture(const std::string& name) { return fixture_path("maps/" + name); }

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Rows listed top (largest y) to bottom, as in the image: row_major_from_top[0] is map row height - 1.
std::vector<std::int8_t> cells_from_top(const std::vector<std::vector<int>>& rows_from_top) {
  std::vector<std::int8_t> cells;
  for (auto row = rows_from_top.rbegin(); row != rows_from_top.rend(); ++row) {
    for (int v : *row) cells.push_back(static_cast<std::int8_t>(v));
  }
  return cells;
}

TEST(MapIo, TrinaryFixtureMatchesHandComputedCells) {
  const OccupancyMap map = read_map(map_fixture("trinary.yaml"));
  EXPECT_EQ(map.width, 4);
  EXPECT_EQ(map.height, 3);
  EXPECT_EQ(map.resolution, 0.05);
  EXPECT_EQ(map.origin.x(), -1.5);
  EXPECT_EQ(map.origin.y(), 2.25);
  EXPECT_EQ(map.origin.theta(), 0.5);
  // Pixels 0 254 205 100 / 50 220 166 255 / 1 2 3 4 with p = (255 - v) / 255, thresholds 0.65, 0.196.
  EXPECT_EQ(map.cells, cells_from_top({{100, 0, -1, -1}, {100, 0, -1, 0}, {100, 100, 100, 100}}));
  EXPECT_EQ(map.at(0, 2), 100);  // top-left pixel (0) is map cell (0, height - 1)
  EXPECT_EQ(map.at(3, 1), 0);    // pixel 255
}

TEST(MapIo, NegateFixtureInvertsThePixels) {
  const OccupancyMap map = read_map(map_fixture("negate.yaml"));
  // With negate p = v / 255: 0 -> 0, 254 -> 100, 205 -> 100 (0.80), 100 -> -1 (0.39), 50 -> -1
  // (0.19608 is not below 0.196), 220 -> 100, 166 -> 100 (0.65098), 255 -> 100, 1..4 -> 0.
  EXPECT_EQ(map.cells, cells_from_top({{0, 100, 100, -1}, {-1, 100, 100, 100}, {0, 0, 0, 0}}));
  EXPECT_EQ(map.resolution, 0.1);
}

TEST(MapIo, ScaleFixtureMapsTheMiddleBandLinearly) {
  const OccupancyMap map = read_map(map_fixture("scale.yaml"));
  // ASCII P2 3 x 2: 153 51 230 / 128 178 80, thresholds free 0.2 and occupied 0.7:
  // 153: p = 0.4 -> 1 + 98 * 0.4 = 40.2 -> 40; 51: p = 0.8 -> 100; 230: p = 0.098 -> 0;
  // 128: p = 0.49804 -> 59.42 -> 59; 178: p = 0.30196 -> 20.98 -> 20; 80: p = 0.68627 -> 96.31 -> 96.
  EXPECT_EQ(map.cells, cells_from_top({{40, 100, 0}, {59, 20, 96}}));
  EXPECT_EQ(map.origin.x(), 10.0);
  EXPECT_EQ(map.origin.y(), -20.0);
  EXPECT_EQ(map.resolution, 0.25);
}

TEST(MapIo, RawFixtureWithNegateStoresInvertedPixelValues) {
  const OccupancyMap map = read_map(map_fixture("raw.yaml"));
  // raw.png 255 200 155 / 154 0 250, negate: 255 - v = 0 55 100 / 101 255 5; above 100 unknown.
  EXPECT_EQ(map.cells, cells_from_top({{0, 55, 100}, {-1, -1, 5}}));
}

TEST(MapIo, MetadataDefaultsAndValues) {
  const MapMetadata meta = read_map_metadata(map_fixture("trinary.yaml"));
  EXPECT_EQ(meta.image, "trinary.pgm");
  EXPECT_EQ(meta.resolution, 0.05);
  EXPECT_EQ(meta.origin, Eigen::Vector3d(-1.5, 2.25, 0.5));
  EXPECT_FALSE(meta.negate);
  EXPECT_EQ(meta.occupied_thresh, 0.65);
  EXPECT_EQ(meta.free_thresh, 0.196);
  EXPECT_EQ(meta.mode, "trinary");  // absent from the file: the default
  EXPECT_EQ(read_map_metadata(map_fixture("scale.yaml")).mode, "scale");
  EXPECT_TRUE(read_map_metadata(map_fixture("raw.yaml")).negate);
}

TEST(MapIo, ColourPngsAreAveragedAndAlphaIgnored) {
  // (255, 0, 0) -> 85, (0, 255, 255) -> 170, (10, 20, 31) -> 20.33 -> 20.
  EXPECT_EQ(read_gray_image(map_fixture("rgb.png")).pixels, (std::vector<std::uint8_t>{85, 170}));
  EXPECT_EQ(read_gray_image(map_fixture("rgba.png")).pixels, (std::vector<std::uint8_t>{85, 20}));
  EXPECT_EQ(read_gray_image(map_fixture("gray_alpha.png")).pixels, (std::vector<std::uint8_t>{17, 240}));
  // Palette (255, 0, 0), (0, 255, 255), (90, 90, 91); indices 2 0 1.
  EXPECT_EQ(read_gray_image(map_fixture("palette.png")).pixels, (std::vector<std::uint8_t>{90, 85, 170}));
  // 1-bit grey: bits 1011000001 -> 255 0 255 255 0 0 0 0 0 255.
  const GrayImage bits = read_gray_image(map_fixture("gray1.png"));
  EXPECT_EQ(bits.width, 10);
  EXPECT_EQ(bits.pixels, (std::vector<std::uint8_t>{255, 0, 255, 255, 0, 0, 0, 0, 0, 255}));
}

TEST(MapIo, SixteenBitPngIsScaledToEightBits) {
  // 0xFFFF -> 255, 0x1234 = 4660 -> 4660 * 255 / 65535 = 18.13 -> 18, 0x8080 = 128 * 257 -> 128.
  const GrayImage image = read_gray_image(map_fixture("gray16.png"));
  EXPECT_EQ(image.width, 3);
  EXPECT_EQ(image.height, 1);
  EXPECT_EQ(image.pixels, (std::vector<std::uint8_t>{255, 18, 128}));
}

TEST(MapIo, PgmWithSmallMaxvalIsScaled) {
  // maxval 15: 0 -> 0, 7 -> 7 * 255 / 15 = 119, 15 -> 255.
  EXPECT_EQ(read_gray_image(map_fixture("maxval15.pgm")).pixels, (std::vector<std::uint8_t>{0, 119, 255}));
}

TEST(MapIo, SixteenBitPgmIsRejected) {
  try {
    read_gray_image(map_fixture("maxval16.pgm"));
    FAIL() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.path(), map_fixture("maxval16.pgm"));
    EXPECT_NE(e.message().find("maxval 65535"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(map_fixture("maxval16.pgm") + ":3: ", 0), 0u) << e.what();
  }
}

TEST(MapIo, PlainAndBinaryPgmWithCommentsReadTheSame) {
  TempDir dir;
  std::ofstream(dir.file("a.pgm")) << "P2\n# comment\n3 # inline comment\n2\n255\n1 2 3\n# row two\n4 5 255\n";
  std::ofstream(dir.file("b.pgm"), std::ios::binary) << "P5\n#c\n3 2\n#d\n255\n"
                                                     << std::string("\x01\x02\x03\x04\x05\xff", 6);
  const GrayImage a = read_gray_image(dir.file("a.pgm"));
  EXPECT_EQ(a, read_gray_image(dir.file("b.pgm")));
  EXPECT_EQ(a.pixels, (std::vector<std::uint8_t>{1, 2, 3, 4, 5, 255}));
}

struct BrokenMap {
  std::string yaml;
  std::string error_file;  // the file named by the error
  std::size_t line;        // 0: the whole file
  std::string message;     // part of the message
};

class BrokenMapTest : public ::testing::TestWithParam<BrokenMap> {};

TEST_P(BrokenMapTest, GivesParseErrorWithPathAndLine) {
  const BrokenMap& c = GetParam();
  const std::string path = map_fixture(c.error_file);
  for (int metadata_only = 0; metadata_only < 2; ++metadata_only) {
    if (metadata_only && c.error_file != c.yaml) continue;  // image errors need read_map
    try {
      if (metadata_only) read_map_metadata(map_fixture(c.yaml));
      else read_map(map_fixture(c.yaml));
      FAIL() << c.yaml << ": no error";
    } catch (const ParseError& e) {
      const std::string prefix = c.line == 0 ? path + ": " : path + ":" + std::to_string(c.line) + ": ";
      EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what() << "\nexpected prefix " << prefix;
      EXPECT_EQ(e.line(), c.line) << e.what();
      EXPECT_NE(e.message().find(c.message), std::string::npos) << e.what();
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Fixtures, BrokenMapTest,
    ::testing::Values(
        BrokenMap{"missing_image_key.yaml", "missing_image_key.yaml", 0, "missing key 'image'"},
        BrokenMap{"image_not_found.yaml", "image_not_found.yaml", 2,
                  "image 'nowhere.pgm' not found (looked for " + map_fixture("nowhere.pgm") + ")"},
        BrokenMap{"negative_resolution.yaml", "negative_resolution.yaml", 3, "resolution must be positive, got -0.05"},
        BrokenMap{"thresholds_swapped.yaml", "thresholds_swapped.yaml", 5,
                  "free_thresh (0.65) must be below occupied_thresh (0.65)"},
        BrokenMap{"origin_two_numbers.yaml", "origin_two_numbers.yaml", 4, "origin must be a list of 3 numbers"},
        BrokenMap{"not_yaml.yaml", "not_yaml.yaml", 3, "not valid YAML"},
        BrokenMap{"prose.yaml", "prose.yaml", 1, "not a map YAML file"},
        BrokenMap{"bad_mode.yaml", "bad_mode.yaml", 6, "mode must be trinary, scale or raw, got 'ternary'"},
        BrokenMap{"nan_origin.yaml", "nan_origin.yaml", 3, "origin must be finite"},
        BrokenMap{"resolution_text.yaml", "resolution_text.yaml", 2, "resolution is not a number: 'fine'"},
        BrokenMap{"truncated_pgm.yaml", "truncated.pgm", 0, "truncated PGM: expected 12 bytes of pixel data, found 7"},
        BrokenMap{"corrupt_png.yaml", "corrupt.png", 0, "corrupt PNG"}));

TEST(MapIo, BinaryGarbageAsYamlIsAParseError) {
  EXPECT_THROW(read_map(map_fixture("not_yaml_binary.yaml")), ParseError);
  EXPECT_THROW(read_map(map_fixture("does_not_exist.yaml")), ParseError);
}

OccupancyMap random_trinary_map(int width, int height, const SE2& origin, double resolution, unsigned seed) {
  std::mt19937 rng(seed);
  OccupancyMap map;
  map.width = width;
  map.height = height;
  map.origin = origin;
  map.resolution = resolution;
  const std::int8_t values[3] = {OccupancyMap::kUnknown, OccupancyMap::kFree, OccupancyMap::kOccupied};
  for (int i = 0; i < width * height; ++i) map.cells.push_back(values[rng() % 3]);
  return map;
}

TEST(MapIo, WriteReadRoundTripIsExactForPgmAndPng) {
  TempDir dir;
  const SE2 origins[] = {SE2(-3.7, 12.125, 2.9), SE2(0.1, -0.2, -3.0), SE2(1e-7, 123456.789, 0.3)};
  const int sizes[][2] = {{7, 5}, {1, 1}, {13, 3}, {2, 31}};
  unsigned seed = 1;
  for (const SE2& origin : origins) {
    for (const auto& size : sizes) {
      for (const std::string image : {"", "picture.png", "sub.pgm"}) {
        const OccupancyMap map = random_trinary_map(size[0], size[1], origin, 0.037 * seed, seed);
        ++seed;
        const std::string yaml = dir.file(std::to_string(seed) + ".yaml");
        write_map(yaml, map, image.empty() ? "" : std::to_string(seed) + image);
        const OccupancyMap back = read_map(yaml);
        EXPECT_TRUE(same_map(back, map)) << yaml;  // cells, size, resolution and origin bit for bit
      }
    }
  }
}

TEST(MapIo, WriteFollowsMapSaverThresholds) {
  TempDir dir;
  OccupancyMap map;
  map.width = 8;
  map.height = 1;
  map.cells = {-1, 0, 19, 20, 50, 65, 66, 100};
  write_map(dir.file("t.yaml"), map);
  // map_saver: v/100 > 0.65 -> 0 (occupied), v/100 < 0.196 -> 254 (free), else 205 (unknown).
  const GrayImage image = read_gray_image(dir.file("t.pgm"));
  EXPECT_EQ(image.pixels, (std::vector<std::uint8_t>{205, 254, 254, 205, 205, 205, 0, 0}));
  EXPECT_EQ(read_map(dir.file("t.yaml")).cells, (std::vector<std::int8_t>{-1, 0, 0, -1, -1, -1, 100, 100}));
}

TEST(MapIo, WrittenYamlIsMapSaverStyle) {
  TempDir dir;
  OccupancyMap map = random_trinary_map(3, 2, SE2(0.1, -2.5, 0.25), 0.05, 7);
  write_map(dir.file("office.yaml"), map);
  EXPECT_TRUE(std::filesystem::exists(dir.file("office.pgm")));
  EXPECT_EQ(read_text(dir.file("office.yaml")),
            "image: office.pgm\nresolution: 0.05\norigin: [0.1, -2.5, 0.25]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n");
  EXPECT_EQ(read_text(dir.file("office.pgm")).substr(0, 11), "P5\n3 2\n255\n");
  // Nothing but the two files: the temporary files were renamed.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()), 2);
}

TEST(MapIo, ImageNameWithSpacesIsQuotedAndReadBack) {
  TempDir dir;
  const OccupancyMap map = random_trinary_map(4, 4, SE2(1, 2, 0), 0.1, 3);
  write_map(dir.file("m.yaml"), map, "my map: \"v2\".png");
  EXPECT_EQ(read_map_metadata(dir.file("m.yaml")).image, "my map: \"v2\".png");
  EXPECT_TRUE(same_map(read_map(dir.file("m.yaml")), map));
}

TEST(MapIo, AbsoluteImagePathInYaml) {
  TempDir dir;
  const OccupancyMap map = random_trinary_map(5, 3, SE2(), 0.05, 4);
  write_map(dir.file("a.yaml"), map);
  std::filesystem::create_directory(dir.path() / "other");
  std::ofstream(dir.file("other/b.yaml")) << "image: " << dir.file("a.pgm")
                                           << "\nresolution: 0.05\norigin: [0, 0, 0]\n"
                                              "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  EXPECT_TRUE(same_map(read_map(dir.file("other/b.yaml")), map));
}

TEST(MapIo, WritingIntoAMissingFolderFailsAndLeavesNothing) {
  TempDir dir;
  const OccupancyMap map = random_trinary_map(2, 2, SE2(), 0.05, 5);
  EXPECT_THROW(write_map(dir.file("nope/m.yaml"), map), Error);
  EXPECT_THROW(write_map(dir.file("m.yaml"), OccupancyMap{}), Error);  // empty map
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(MapIo, GrayAndRgbImagesRoundTrip) {
  TempDir dir;
  std::mt19937 rng(11);
  GrayImage gray{17, 9, {}};
  for (int i = 0; i < gray.width * gray.height; ++i) gray.pixels.push_back(static_cast<std::uint8_t>(rng()));
  write_pgm(dir.file("g.pgm"), gray);
  write_png(dir.file("g.png"), gray);
  EXPECT_EQ(read_gray_image(dir.file("g.pgm")), gray);
  EXPECT_EQ(read_gray_image(dir.file("g.png")), gray);
  RgbImage rgb(5, 11);
  for (auto& v : rgb.rgb) v = static_cast<std::uint8_t>(rng());
  write_png(dir.file("c.png"), rgb);
  EXPECT_EQ(read_png_rgb(dir.file("c.png")), rgb);
  // Grey read of a colour PNG: the rounded mean of R, G, B.
  const GrayImage mean = read_gray_image(dir.file("c.png"));
  for (std::size_t i = 0; i < mean.pixels.size(); ++i) {
    const int sum = rgb.rgb[3 * i] + rgb.rgb[3 * i + 1] + rgb.rgb[3 * i + 2];
    EXPECT_EQ(mean.pixels[i], (sum + 1) / 3);
  }
  // RGB read of a grey PNG replicates the grey level.
  const RgbImage replicated = read_png_rgb(dir.file("g.png"));
  for (std::size_t i = 0; i < gray.pixels.size(); ++i) {
    EXPECT_EQ(replicated.rgb[3 * i], gray.pixels[i]);
    EXPECT_EQ(replicated.rgb[3 * i + 2], gray.pixels[i]);
  }
  EXPECT_THROW(read_png_rgb(dir.file("g.pgm")), ParseError);
}

TEST(MapIo, DamagedImagesNeverCrash) {
  // Flip random bytes of valid files: every read either succeeds or throws ParseError.
  TempDir dir;
  std::mt19937 rng(2024);
  GrayImage gray{23, 19, std::vector<std::uint8_t>(23 * 19, 77)};
  write_pgm(dir.file("g.pgm"), gray);
  write_png(dir.file("g.png"), gray);
  int errors = 0;
  for (const std::string name : {"g.pgm", "g.png"}) {
    const std::string original = read_text(dir.file(name));
    for (int trial = 0; trial < 300; ++trial) {
      std::string damaged = original;
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int f = 0; f < flips; ++f) damaged[rng() % std::min<std::size_t>(damaged.size(), 120)] = static_cast<char>(rng());
      if (trial % 3 == 0) damaged.resize(rng() % damaged.size());
      // A new file each time: truncating an existing file is slow on some file systems.
      const std::string path = dir.file(std::to_string(trial) + name);
      std::ofstream(path, std::ios::binary) << damaged;
      try {
        const GrayImage image = read_gray_image(path);
        EXPECT_EQ(image.pixels.size(), static_cast<std::size_t>(image.width) * image.height);
      } catch (const ParseError& e) {
        EXPECT_EQ(e.path(), path);
        ++errors;
      }
    }
  }
  EXPECT_GT(errors, 100);
}

}  // namespace
}  // namespace slam2d
