// SPDX-License-Identifier: BSD-3-Clause
// The 2015 chain without wheel odometry (map --method hector+graph, docs/methods/fusion.md) on the
// logs of Kuemmerle et al. 2009: the fused trajectory's relation error within a bound a little
// above what was measured (Intel 0.0186, ACES 0.0696, FR079 0.0374 m), no worse than the sparse
// trajectory's on the relations that one covers, and better than Hector's dense one where Hector
// drifts; and the chain's first step, Hector without odometry, makes no jump.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "slam2d/core/trajectory.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::run_command;

struct ChainLog {
  const char* name;
  double max_fused;  // m, mean translational relation error of the fused trajectory
  // Largest ratio of the fused trajectory's error to Hector's dense one: 1 where Hector drifts
  // (Intel, ACES); on FR079 it does not, and without a tracker jump to smooth (issue 40) Hector
  // alone is a little better than the chain (0.0352 against 0.0366 m).
  double max_over_hector;
};

void PrintTo(const ChainLog& log, std::ostream* os) { *os << log.name; }

// The relations both of whose stamps `trajectory` has a pose for (within 1 ms).
std::vector<Relation> covered(const std::vector<Relation>& relations, const Trajectory& trajectory) {
  const StampIndex index(trajectory);
  std::vector<Relation> kept;
  for (const Relation& relation : relations) {
    if (index.nearest(relation.stamp_from, 1e-3) && index.nearest(relation.stamp_to, 1e-3)) kept.push_back(relation);
  }
  return kept;
}

class PipelineRealData : public ::testing::TestWithParam<ChainLog> {};

TEST_P(PipelineRealData, TheFusedTrajectoryIsDenseAndNoWorseThanTheSparseOne) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  const std::string name = GetParam().name;
  TempDir out;
  const CommandResult result = run_command(test::cli_command("map --quiet " + (data / name / (name + ".clf.gz")).string() +
                                                             " --method hector+graph --trajectory-frame sensor --out " +
                                                             out.path().string()));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const std::vector<Relation> relations = read_relations((data / name / (name + ".relations")).string());
  const Trajectory fused = read_trajectory(out.file("trajectory.txt"));
  const Trajectory sparse = read_trajectory(out.file("sparse_trajectory.txt"));
  const Trajectory hector = read_trajectory(out.file("hector_trajectory.txt"));
  EXPECT_EQ(fused.size(), hector.size());
  const Trajectory sorted = fused.sorted_by_stamp();
  const double duration = sorted.back().stamp - sorted.front().stamp;
  EXPECT_LE(static_cast<double>(sparse.size()), 3.0 * duration + 1.0) << "the sparse method saw 3 scans a second";
  EXPECT_LT(sparse.size(), fused.size());

  const RelationErrorResult all = relation_error(fused, relations);
  EXPECT_EQ(all.missing, 0u) << "dense: every relation has its poses";
  EXPECT_LT(all.translation.mean, GetParam().max_fused);
  const std::vector<Relation> subset = covered(relations, sparse);
  ASSERT_GT(subset.size(), 100u);
  EXPECT_LE(relation_error(fused, subset).translation.mean, relation_error(sparse, subset).translation.mean);
  EXPECT_LE(all.translation.mean, GetParam().max_over_hector * relation_error(hector, relations).translation.mean);
}

// The chain's first step must not pass on a jump as motion: Hector without odometry, where a scan
// fits poorly, searches every heading, and a heading that fits only a little better must not win.
// On FR079 one did (a 1.6 rad turn at 2109.9 s and back two scans later), and the chain had to
// smooth it away. A step of at most 1 s (a gap's may turn far) turns less than 1 rad.
TEST(PipelineRealDataTracker, HectorWithoutOdometryMakesNoJump) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  for (const std::string name : {"fr079", "aces"}) {
    TempDir out;
    const CommandResult result = run_command(test::cli_command("map --quiet " + (data / name / (name + ".clf.gz")).string() +
                                                               " --method hector --no-odometry --out " + out.path().string()));
    ASSERT_EQ(result.exit_code, 0) << result.errors;
    const Trajectory hector = read_trajectory(out.file("trajectory.txt"));
    double largest_turn = 0.0;
    for (std::size_t i = 1; i < hector.size(); ++i) {
      if (hector[i].stamp - hector[i - 1].stamp > 1.0) continue;
      largest_turn = std::max(largest_turn, std::abs(hector[i - 1].pose.between(hector[i].pose).theta()));
    }
    EXPECT_LT(largest_turn, 1.0) << name;
    const std::vector<Relation> relations = read_relations((data / name / (name + ".relations")).string());
    EXPECT_LT(relation_error(hector, relations).translation.mean, name == "aces" ? 0.2 : 0.04) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Kuemmerle2009, PipelineRealData,
                         ::testing::Values(ChainLog{"intel", 0.024, 1.0}, ChainLog{"aces", 0.09, 1.0},
                                           ChainLog{"fr079", 0.045, 1.1}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace slam2d
