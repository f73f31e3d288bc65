// SPDX-License-Identifier: BSD-3-Clause
// Real relations files (Kuemmerle et al. 2009) and public pose graphs: counts from
// $SLAM2D_DATA/README.md, hand-checked first lines, exact write -> read on the big graphs.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>

#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/io/relations.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

// Runs `read` and prints how long it took (the README asks for well under a second per graph).
template <typename Read>
auto timed(const std::string& label, Read read) {
  const auto start = std::chrono::steady_clock::now();
  auto result = read();
  const std::chrono::duration<double, std::milli> elapsed = std::chrono::steady_clock::now() - start;
  std::cout << "[ timing ] " << label << ": " << elapsed.count() << " ms\n";
  return result;
}

TEST(FilesRealData, EveryRelationsFileParsesWithTheReadmeCount) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  struct RelationsCase {
    std::string file;
    std::size_t count;
    double log_duration;  // s, last scan stamp minus first in the matching .clf.gz (README)
  };
  const std::vector<RelationsCase> cases = {{"intel/intel.relations", 2984, 2691.3},
                                            {"aces/aces.relations", 1279, 1365.5},
                                            {"fr079/fr079.relations", 1685, 1061.4}};
  for (const RelationsCase& c : cases) {
    SCOPED_TRACE(c.file);
    const auto relations = timed(c.file, [&] { return read_relations((data / c.file).string()); });
    ASSERT_EQ(relations.size(), c.count);
    EXPECT_EQ(relations.back().line, c.count);  // no comments or blank lines in these files
    // Every stamp is finite, the two stamps of a relation differ, and all stamps fit in the log's span.
    std::size_t bad = 0;
    double first = relations[0].stamp_from;
    double last = first;
    for (const Relation& r : relations) {
      const bool ok = std::isfinite(r.stamp_from) && std::isfinite(r.stamp_to) && r.stamp_from != r.stamp_to &&
                      r.T_from_to.vector().allFinite();
      bad += ok ? 0 : 1;
      first = std::min({first, r.stamp_from, r.stamp_to});
      last = std::max({last, r.stamp_from, r.stamp_to});
    }
    EXPECT_EQ(bad, 0u);
    EXPECT_LE(last - first, c.log_duration);
  }
  // First line of intel.relations: "976052905.167303 976052911.885496 -0.056990 -0.128430 0 0 0 -1.682210".
  const auto intel = read_relations((data / "intel/intel.relations").string());
  EXPECT_EQ(intel[0].stamp_from, 976052905.167303);
  EXPECT_EQ(intel[0].stamp_to, 976052911.885496);
  EXPECT_EQ(intel[0].T_from_to.x(), -0.056990);
  EXPECT_EQ(intel[0].T_from_to.y(), -0.128430);
  EXPECT_EQ(intel[0].T_from_to.theta(), -1.682210);
}

struct GraphCase {
  std::string file;
  PoseGraphFormat format;
  std::size_t vertices;
  std::size_t edges;
};

TEST(FilesRealData, EveryPoseGraphParsesWithTheReadmeCounts) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::vector<GraphCase> cases = {
      {"se-sync/intel.g2o", PoseGraphFormat::kG2o, 1728, 2512},
      {"se-sync/manhattan.g2o", PoseGraphFormat::kG2o, 0, 5453},  // edges only
      {"se-sync/city10000.g2o", PoseGraphFormat::kG2o, 10000, 20687},
      {"vertigo/intel.g2o", PoseGraphFormat::kG2o, 943, 1837},
      {"vertigo/manhattanOlson3500.olson.g2o", PoseGraphFormat::kG2o, 3500, 5598},
      {"vertigo/manhattanOlson3500.g2o", PoseGraphFormat::kG2o, 3500, 5598},
      {"vertigo/ring.g2o", PoseGraphFormat::kG2o, 434, 459},
      {"vertigo/ringCity.g2o", PoseGraphFormat::kG2o, 2361, 3261},
      {"vertigo/groundTruth/ring.g2o", PoseGraphFormat::kG2o, 434, 459},
      {"vertigo/groundTruth/ringCity.g2o", PoseGraphFormat::kG2o, 2361, 3261},
      {"hog-man/w10000.graph.gz", PoseGraphFormat::kToro, 10000, 64311},
  };
  for (const GraphCase& c : cases) {
    SCOPED_TRACE(c.file);
    const PoseGraphFile graph = timed(c.file, [&] { return read_pose_graph((data / "posegraphs" / c.file).string()); });
    EXPECT_EQ(graph.format, c.format);
    EXPECT_EQ(graph.vertices.size(), c.vertices);
    EXPECT_EQ(graph.edges.size(), c.edges);
    EXPECT_EQ(graph.skipped_lines, 0u);
    for (const GraphEdge& e : graph.edges) {
      ASSERT_TRUE(e.information.isApprox(e.information.transpose(), 0.0)) << e.from << " -> " << e.to;
    }
  }
}

TEST(FilesRealData, HandCheckedFirstLinesOfTwoGraphs) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  // "VERTEX2 0 1.26 -2.3 0.699" and "EDGE2 0 1 0.999 -0.0631 0.0205 100 0 100 400 0 0" (TORO order).
  const PoseGraphFile w10000 = read_pose_graph((data / "posegraphs/hog-man/w10000.graph.gz").string());
  EXPECT_EQ(w10000.vertices[0].pose.x(), 1.26);
  EXPECT_EQ(w10000.vertices[0].pose.theta(), 0.699);
  EXPECT_EQ(w10000.edges[0].T_from_to.y(), -0.0631);
  EXPECT_EQ(w10000.edges[0].information.diagonal(), Eigen::Vector3d(100.0, 100.0, 400.0));
  // "EDGE_SE2 0 1 0.144012 -0.004462 -0.017453 115.187 -9.86523 -7.085 347.418 185.36 224.616" (g2o order).
  const PoseGraphFile intel = read_pose_graph((data / "posegraphs/se-sync/intel.g2o").string());
  Eigen::Matrix3d expected;
  expected << 115.187, -9.86523, -7.085, -9.86523, 347.418, 185.36, -7.085, 185.36, 224.616;
  EXPECT_EQ(intel.edges[0].information, expected);
  EXPECT_EQ(intel.edges[0].T_from_to.theta(), -0.017453);
}

TEST(FilesRealData, BigGraphsWriteThenReadExactly) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  test::TempDir dir;
  for (const std::string file : {"se-sync/city10000.g2o", "hog-man/w10000.graph.gz"}) {
    SCOPED_TRACE(file);
    const PoseGraphFile graph = read_pose_graph((data / "posegraphs" / file).string());
    const std::string copy = dir.file("copy.g2o");
    timed("write_g2o " + file, [&] { write_g2o(copy, graph); return 0; });
    const PoseGraphFile back = read_pose_graph(copy);
    ASSERT_EQ(back.vertices.size(), graph.vertices.size());
    ASSERT_EQ(back.edges.size(), graph.edges.size());
    for (std::size_t i = 0; i < graph.vertices.size(); ++i) {
      ASSERT_EQ(back.vertices[i].pose.vector(), graph.vertices[i].pose.vector()) << i;
    }
    for (std::size_t i = 0; i < graph.edges.size(); ++i) {
      ASSERT_EQ(back.edges[i].T_from_to.vector(), graph.edges[i].T_from_to.vector()) << i;
      ASSERT_EQ(back.edges[i].information, graph.edges[i].information) << i;
    }
  }
}

}  // namespace
}  // namespace slam2d
