// SPDX-License-Identifier: BSD-3-Clause
// Pose graph files (g2o and TORO): hand-computed parse, exact round trips, malformed input.
#include "slam2d/io/pose_graph_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>

#include "slam2d/core/error.hpp"
#include "slam2d/core/rng.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::fixture_path;
using test::TempDir;
using test::expect_parse_error;

void expect_same_pose(const SE2& actual, const SE2& expected) {
  EXPECT_EQ(actual.x(), expected.x());
  EXPECT_EQ(actual.y(), expected.y());
  EXPECT_EQ(actual.theta(), expected.theta());
}

// Vertices, edges and FIX ids equal, bit for bit.
void expect_same_graph(const PoseGraphFile& actual, const PoseGraphFile& expected) {
  ASSERT_EQ(actual.vertices.size(), expected.vertices.size());
  ASSERT_EQ(actual.edges.size(), expected.edges.size());
  for (std::size_t i = 0; i < actual.vertices.size(); ++i) {
    SCOPED_TRACE("vertex " + std::to_string(i));
    EXPECT_EQ(actual.vertices[i].id, expected.vertices[i].id);
    expect_same_pose(actual.vertices[i].pose, expected.vertices[i].pose);
  }
  for (std::size_t i = 0; i < actual.edges.size(); ++i) {
    SCOPED_TRACE("edge " + std::to_string(i));
    EXPECT_EQ(actual.edges[i].from, expected.edges[i].from);
    EXPECT_EQ(actual.edges[i].to, expected.edges[i].to);
    expect_same_pose(actual.edges[i].T_from_to, expected.edges[i].T_from_to);
    EXPECT_TRUE(actual.edges[i].information == expected.edges[i].information) << actual.edges[i].information;
  }
  EXPECT_EQ(actual.fixed, expected.fixed);
}

// The graph both fixtures describe, typed in by hand.
PoseGraphFile small_graph() {
  PoseGraphFile graph;
  graph.vertices = {{0, SE2(0.0, 0.0, 0.0)}, {1, SE2(1.0, 0.0, 0.5)}, {2, SE2(1.5, 2.25, -1.0)}};
  Eigen::Matrix3d i01, i12, i20;
  i01 << 11, 12, 13, 12, 22, 23, 13, 23, 33;
  i12 << 100, 0, 0, 0, 200, 0, 0, 0, 300;
  i20 << 1, -0.5, 0.25, -0.5, 2, -0.75, 0.25, -0.75, 4;
  graph.edges = {{0, 1, SE2(1.0, 0.0, 0.5), i01}, {1, 2, SE2(0.25, -0.5, 1.5), i12}, {2, 0, SE2(-2.0, 1.0, 3.0), i20}};
  return graph;
}

PoseGraphFile random_graph(std::size_t n) {
  Rng rng(3);
  PoseGraphFile graph;
  for (std::size_t i = 0; i < n; ++i) {
    graph.vertices.push_back({static_cast<int>(i) * 3 - 7, SE2(rng.uniform(-1e3, 1e3), rng.gaussian(0.0, 1e-3),
                                                               rng.uniform(-std::numbers::pi, std::numbers::pi))});
    Eigen::Matrix3d information;  // symmetric, with awkward digits
    for (int row = 0; row < 3; ++row) {
      for (int col = row; col < 3; ++col) information(row, col) = information(col, row) = rng.gaussian(0.0, 1e3);
    }
    graph.edges.push_back({static_cast<int>(i), static_cast<int>((i * 7 + 1) % n),
                           SE2(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0), rng.uniform(-4.0, 4.0)), information});
  }
  graph.fixed = {-7, 2};
  return graph;
}

TEST(PoseGraphIo, ReadsG2oFixture) {
  const PoseGraphFile graph = read_pose_graph(fixture_path("graphs/small.g2o"));
  EXPECT_EQ(graph.format, PoseGraphFormat::kG2o);
  expect_same_graph(graph, [] {
    PoseGraphFile g = small_graph();
    g.fixed = {0};
    return g;
  }());
  EXPECT_EQ(graph.skipped_lines, 3u);  // PARAMS_SE2OFFSET, VERTEX_XY, EDGE_SE2_XY
  // Upper triangle row-major: "11 12 13 22 23 33".
  EXPECT_EQ(graph.edges[0].information(0, 2), 13.0);
  EXPECT_EQ(graph.edges[0].information(2, 0), 13.0);
  EXPECT_EQ(graph.edges[0].information(1, 2), 23.0);
}

TEST(PoseGraphIo, ReadsToroFixtureWithToroInformationOrder) {
  const PoseGraphFile graph = read_pose_graph(fixture_path("graphs/small.toro"));
  EXPECT_EQ(graph.format, PoseGraphFormat::kToro);
  EXPECT_EQ(graph.skipped_lines, 0u);
  expect_same_graph(graph, small_graph());
  // "I11 I12 I22 I33 I13 I23" = "11 12 22 33 13 23": the 33 is the fourth number, 13 the fifth.
  const Eigen::Matrix3d& info = graph.edges[0].information;
  EXPECT_EQ(info(1, 1), 22.0);
  EXPECT_EQ(info(2, 2), 33.0);
  EXPECT_EQ(info(0, 2), 13.0);
  EXPECT_EQ(info(2, 1), 23.0);
}

TEST(PoseGraphIo, G2oAndToroWriteThenReadIsExact) {
  TempDir dir;
  const PoseGraphFile graph = random_graph(500);
  write_g2o(dir.file("g.g2o"), graph);
  const PoseGraphFile g2o = read_pose_graph(dir.file("g.g2o"));
  EXPECT_EQ(g2o.format, PoseGraphFormat::kG2o);
  expect_same_graph(g2o, graph);
  write_toro(dir.file("g.graph"), graph);
  const PoseGraphFile toro = read_pose_graph(dir.file("g.graph"));
  EXPECT_EQ(toro.format, PoseGraphFormat::kToro);
  expect_same_graph(toro, graph);
}

TEST(PoseGraphIo, ReadsGzipCompressedGraphs) {
  TempDir dir;
  const PoseGraphFile graph = random_graph(100);
  write_toro(dir.file("g.graph.gz"), graph);
  std::ifstream gz(dir.file("g.graph.gz"), std::ios::binary);
  EXPECT_EQ(gz.get(), 0x1f);  // gzip magic bytes: the reader really decompressed
  EXPECT_EQ(gz.get(), 0x8b);
  expect_same_graph(read_pose_graph(dir.file("g.graph.gz")), graph);
}

TEST(PoseGraphIo, ConvertsBetweenFormats) {
  TempDir dir;
  const PoseGraphFile toro = read_pose_graph(fixture_path("graphs/small.toro"));
  write_g2o(dir.file("small.g2o"), toro);
  expect_same_graph(read_pose_graph(dir.file("small.g2o")), small_graph());
  std::ifstream in(dir.file("small.g2o"));
  std::string line;
  for (int i = 0; i < 4; ++i) std::getline(in, line);
  EXPECT_EQ(line, "EDGE_SE2 0 1 1 0 0.5 11 12 13 22 23 33");
}

TEST(PoseGraphIo, EmptyGraphRoundTrips) {
  TempDir dir;
  write_g2o(dir.file("empty.g2o"), PoseGraphFile{});
  const PoseGraphFile graph = read_pose_graph(dir.file("empty.g2o"));
  EXPECT_TRUE(graph.vertices.empty());
  EXPECT_TRUE(graph.edges.empty());
}

TEST(PoseGraphIo, MalformedFilesGiveParseErrorWithPathAndLine) {
  expect_parse_error(read_pose_graph, fixture_path("graphs/mixed.g2o"), 4, "mixed formats: TORO tag EDGE2 in a g2o file (g2o since line 1)");
  expect_parse_error(read_pose_graph, fixture_path("graphs/duplicate_vertex.g2o"), 4, "duplicate vertex id 0 (first on line 1)");
  expect_parse_error(read_pose_graph, fixture_path("graphs/short_edge.toro"), 2, "EDGE2: expected 11 values");
  expect_parse_error(read_pose_graph, fixture_path("graphs/short_edge.toro"), 2, "got 10");
  expect_parse_error(read_pose_graph, fixture_path("graphs/nan_information.g2o"), 2, "NaN in I13");
  expect_parse_error(read_pose_graph, fixture_path("graphs/bad_id.g2o"), 2, "vertex id is not an integer: '1.5'");
  expect_parse_error(read_pose_graph, fixture_path("graphs/empty_fix.g2o"), 2, "FIX: expected at least one vertex id");
}

TEST(PoseGraphIo, MissingFileGivesErrorNamingThePath) {
  const std::string path = fixture_path("graphs/no_such_file.g2o");
  try {
    read_pose_graph(path);
    FAIL() << "no Error";
  } catch (const ParseError&) {
    FAIL() << "a missing file is not a parse error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(PoseGraphIo, WritersRefuseNonFiniteValuesAndLeaveNoFile) {
  TempDir dir;
  PoseGraphFile graph = small_graph();
  graph.edges[1].information(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(write_g2o(dir.file("a.g2o"), graph), Error);
  EXPECT_THROW(write_toro(dir.file("a.graph"), graph), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.g2o")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.graph")));
}

}  // namespace
}  // namespace slam2d
