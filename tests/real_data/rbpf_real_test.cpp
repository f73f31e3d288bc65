// SPDX-License-Identifier: BSD-3-Clause
// Rao-Blackwellized particle filter SLAM (slam/rbpf) on the FR079 log of Kuemmerle et al. 2009,
// the cheapest log that still shows the point: 5 particles (about 12 s of CPU) beat the RBPF
// column of that paper (FR079 0.061 m), and one seed gives one trajectory. The 30-particle figures
// on every log are in docs/methods/rbpf.md (they take 20-60 s each).

#include <gtest/gtest.h>

#include <variant>
#include <vector>

#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

TEST(RbpfRealData, Fr079WithFiveParticlesBeatsTheRbpfColumnOfKuemmerle2009) {
  SLAM2D_REQUIRE_REAL_DATA(data);
  std::vector<LaserMessage> scans;
  CarmenReader reader((data / "fr079/fr079.clf.gz").string());
  while (auto message = reader.next()) {
    if (auto* laser = std::get_if<LaserMessage>(&*message)) scans.push_back(std::move(*laser));
  }
  RbpfSlam slam({.particles = 5, .seed = 1});
  for (const LaserMessage& laser : scans) slam.add_scan(laser.scan, laser.odom_pose);
  const Trajectory trajectory = slam.trajectory();
  ASSERT_EQ(trajectory.size(), scans.size());
  const RelationErrorResult result = relation_error(trajectory, read_relations((data / "fr079/fr079.relations").string()));
  EXPECT_EQ(result.missing, 0u);
  // Measured 0.036 m and 0.45 deg; the RBPF column of Kuemmerle et al. 2009: 0.061 m.
  EXPECT_LT(result.translation.mean, 0.061);
  EXPECT_LT(result.rotation_deg.mean, 0.6);
  EXPECT_GT(slam.stats().resamplings, 0u);
  EXPECT_LT(slam.stats().resamplings, slam.stats().updates / 4);  // selective resampling
}

}  // namespace
}  // namespace slam2d
