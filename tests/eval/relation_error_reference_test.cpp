// SPDX-License-Identifier: BSD-3-Clause
// Cross-check of the C++ relation error (Kuemmerle et al. 2009) against the independent Python
// implementation in tools/relation_error_reference.py, on a generated trajectory and relations.

#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <regex>
#include <string>
#include <vector>

#include "slam2d/core/rng.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

std::string shortest(double value) {
  char buffer[64];
  const auto end = std::to_chars(buffer, buffer + sizeof(buffer), value).ptr;
  return std::string(buffer, end);
}

// Test-local writers, so that this test does not depend on the io module's writers.
void write_poses(const std::string& path, const Trajectory& trajectory) {
  std::ofstream out(path);
  out << "# t x y theta\n";
  for (const StampedPose& p : trajectory) {
    out << shortest(p.stamp) << ' ' << shortest(p.pose.x()) << ' ' << shortest(p.pose.y()) << ' '
        << shortest(p.pose.theta()) << '\n';
  }
}

void write_relation_lines(const std::string& path, const std::vector<Relation>& relations) {
  std::ofstream out(path);
  for (const Relation& r : relations) {
    out << shortest(r.stamp_from) << ' ' << shortest(r.stamp_to) << ' ' << shortest(r.T_from_to.x()) << ' '
        << shortest(r.T_from_to.y()) << " 0 0 0 " << shortest(r.T_from_to.theta()) << '\n';
  }
}

std::map<std::string, double> parse_flat_json(const std::string& text) {
  std::map<std::string, double> values;
  const std::regex entry("\"([a-z_0-9]+)\"\\s*:\\s*([-+0-9.eE]+)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it) {
    values[(*it)[1]] = std::stod((*it)[2]);
  }
  return values;
}

// A random walk at large absolute stamps (like the real logs), shuffled; relations between random
// pose pairs, with noisy truth (some with turns near +-pi), some at stamps with no pose, some at
// stamps a little off the pose's stamp.
struct Generated {
  Trajectory estimate;
  std::vector<Relation> relations;
};

Generated generate(std::uint64_t seed) {
  Rng rng(seed);
  std::vector<StampedPose> poses;
  SE2 pose(10.0, -5.0, 1.0);
  for (int k = 0; k < 300; ++k) {
    poses.push_back({976052857.337284 + 0.2 * k, pose});
    pose = pose * SE2(rng.uniform(0.0, 0.4), rng.uniform(-0.05, 0.05), rng.uniform(-0.6, 0.6));
  }
  Generated g;
  for (int k = 0; k < 400; ++k) {
    const std::size_t i = rng.uniform_index(poses.size());
    const std::size_t j = rng.uniform_index(poses.size());
    SE2 truth = poses[i].pose.between(poses[j].pose) *
                SE2(rng.gaussian(0.0, 0.1), rng.gaussian(0.0, 0.1), rng.gaussian(0.0, 0.05));
    if (k % 10 == 0) truth = truth * SE2(0.0, 0.0, std::numbers::pi - rng.uniform(0.0, 0.01));
    const double jitter = rng.uniform(-0.0009, 0.0009);
    const double t2 = (k % 17 == 0) ? poses[j].stamp + 0.05 : poses[j].stamp;  // no pose at t2
    g.relations.push_back({poses[i].stamp + jitter, t2, truth, 0});
  }
  for (std::size_t k = 0; k + 1 < poses.size(); k += 3) std::swap(poses[k], poses[poses.size() - 1 - k]);
  g.estimate = Trajectory(poses);
  return g;
}

TEST(RelationErrorReference, PythonReferenceAgreesWithCpp) {
  const Generated g = generate(2009);
  test::TempDir dir;
  write_poses(dir.file("estimate.txt"), g.estimate);
  write_relation_lines(dir.file("truth.relations"), g.relations);
  const RelationErrorResult r = relation_error(g.estimate, g.relations);
  ASSERT_GT(r.missing, 0u);
  ASSERT_GT(r.relations, 300u);

  const test::CommandResult python =
      test::run_command("python3 tools/relation_error_reference.py '" + dir.file("estimate.txt") + "' '" +
                        dir.file("truth.relations") + "'");
  ASSERT_EQ(python.exit_code, 0) << python.errors;
  const auto json = parse_flat_json(python.output);
  ASSERT_EQ(json.size(), 10u) << python.output;
  EXPECT_EQ(json.at("relations"), static_cast<double>(r.relations));
  EXPECT_EQ(json.at("missing"), static_cast<double>(r.missing));
  const std::vector<std::pair<std::string, double>> expected{{"trans_mean", r.translation.mean},
                                                             {"trans_std", r.translation.std},
                                                             {"trans_max", r.translation.max},
                                                             {"rot_mean_deg", r.rotation_deg.mean},
                                                             {"rot_std_deg", r.rotation_deg.std},
                                                             {"rot_max_deg", r.rotation_deg.max},
                                                             {"trans_sq_mean", r.translation_squared.mean},
                                                             {"rot_sq_mean_deg2", r.rotation_squared_deg2.mean}};
  for (const auto& [key, value] : expected) EXPECT_NEAR(json.at(key), value, 1e-9) << key;
  EXPECT_GT(r.rotation_deg.max, 170.0);  // the near-half-turn relations were evaluated
}

TEST(RelationErrorReference, PythonReferenceHonoursTheToleranceAndRejectsGarbage) {
  test::TempDir dir;
  Trajectory estimate;
  estimate.push_back(10.0, SE2(0.0, 0.0, 0.0));
  estimate.push_back(20.25, SE2(1.0, 0.0, 0.0));
  write_poses(dir.file("estimate.txt"), estimate);
  write_relation_lines(dir.file("truth.relations"), {{10.0, 20.0, SE2(1.0, 0.0, 0.0), 0}});
  const std::string command = "python3 tools/relation_error_reference.py '" + dir.file("estimate.txt") + "' '" +
                              dir.file("truth.relations") + "'";
  const auto inside = parse_flat_json(test::run_command(command + " --tolerance 0.25").output);
  EXPECT_EQ(inside.at("relations"), 1.0);
  const auto outside = parse_flat_json(test::run_command(command + " --tolerance 0.2499").output);
  EXPECT_EQ(outside.at("relations"), 0.0);
  EXPECT_EQ(outside.at("missing"), 1.0);

  std::ofstream(dir.file("bad.txt")) << "1 2 nan 4\n";
  const test::CommandResult bad = test::run_command("python3 tools/relation_error_reference.py '" +
                                                    dir.file("bad.txt") + "' '" + dir.file("truth.relations") + "'");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.errors.find("bad.txt:1:"), std::string::npos) << bad.errors;
}

}  // namespace
}  // namespace slam2d
