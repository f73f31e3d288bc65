// SPDX-License-Identifier: BSD-3-Clause
// slam2d optimize: a small inconsistent g2o loop optimised and written back (g2o, TORO, gzip), the
// written poses scoring the reported chi2, edges-only input, false closures added by slam2d spoil
// and rejected by GNC, and bad input giving "PATH:LINE:", a non-zero exit and no output.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "slam2d/io/pose_graph_io.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::json_number;
using test::run_command;

using test::slam2d;

// A 2 m square in four 1 m sides whose odometry says 1.1 m, closed by a loop edge to the start.
const char* const kSquare =
    "VERTEX_SE2 0 0 0 0\n"
    "VERTEX_SE2 1 1.1 0 1.5707963267948966\n"
    "VERTEX_SE2 2 1.1 1.1 3.141592653589793\n"
    "VERTEX_SE2 3 0 1.1 -1.5707963267948966\n"
    "EDGE_SE2 0 1 1.1 0 1.5707963267948966 100 0 0 100 0 400\n"
    "EDGE_SE2 1 2 1.1 0 1.5707963267948966 100 0 0 100 0 400\n"
    "EDGE_SE2 2 3 1.1 0 1.5707963267948966 100 0 0 100 0 400\n"
    "EDGE_SE2 3 0 1.1 0 1.5707963267948966 100 0 0 100 0 400\n"
    "EDGE_SE2 0 2 1 1 3.141592653589793 1000 0 0 1000 0 1000\n";

std::string write_file(const TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::ofstream(path) << text;
  return path;
}

TEST(OptimizeCli, OptimisesAndWritesTheGraphBack) {
  TempDir dir;
  const std::string input = write_file(dir, "square.g2o", kSquare);
  const std::string out = dir.file("out/square_opt.g2o");
  const CommandResult result = run_command(slam2d("optimize --json " + input + " --out " + out));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  EXPECT_EQ(json_number(result.output, "nodes"), 4.0);
  EXPECT_EQ(json_number(result.output, "edges"), 5.0);
  const double initial = json_number(result.output, "given_chi2").value_or(-1.0);
  const double final_chi2 = json_number(result.output, "final_chi2").value_or(-1.0);
  EXPECT_GT(initial, 10.0);  // the diagonal disagrees with the square's sides
  EXPECT_GT(final_chi2, 0.0);
  EXPECT_LT(final_chi2, 0.5 * initial);
  EXPECT_GT(json_number(result.output, "iterations").value_or(0.0), 0.0);
  for (const char* key : {"cpu_s", "wall_s"}) EXPECT_GE(json_number(result.output, key).value_or(-1.0), 0.0) << key;
  EXPECT_NE(result.output.find("\"converged\": true"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("\"format\": \"g2o\""), std::string::npos) << result.output;

  const PoseGraphFile written = read_pose_graph(out);
  EXPECT_EQ(written.format, PoseGraphFormat::kG2o);
  ASSERT_EQ(written.vertices.size(), 4u);
  EXPECT_EQ(written.edges.size(), 5u);
  EXPECT_EQ(written.vertices[0].pose.vector(), Eigen::Vector3d::Zero());  // node 0 is the gauge

  // The written poses score the reported chi2 (numbers are written exactly), and are optimal.
  const CommandResult again = run_command(slam2d("optimize --json " + out + " --out " + dir.file("again.g2o")));
  ASSERT_EQ(again.exit_code, 0) << again.errors;
  EXPECT_EQ(json_number(again.output, "given_chi2"), final_chi2);
  EXPECT_NEAR(json_number(again.output, "final_chi2").value_or(-1.0), final_chi2, 1e-9 * final_chi2);
}

// The start: by default the one of the file's poses and the orientations-first estimate with the
// lower chi2, named; --initial given alone computes no estimate; a start it does not know
// is refused.
TEST(OptimizeCli, TheStartIsChosenAndReported) {
  TempDir dir;
  const std::string input = write_file(dir, "square.g2o", kSquare);
  const CommandResult better = run_command(slam2d("optimize --json " + input + " --out " + dir.file("better.g2o")));
  const CommandResult each =
      run_command(slam2d("optimize --json --initial both " + input + " --out " + dir.file("each.g2o")));
  ASSERT_EQ(each.exit_code, 0) << each.errors;
  ASSERT_EQ(better.exit_code, 0) << better.errors;
  EXPECT_TRUE(json_number(better.output, "given_chi2").has_value()) << better.output;
  EXPECT_TRUE(json_number(better.output, "estimated_start_chi2").has_value()) << better.output;
  EXPECT_TRUE(better.output.find("\"initial_guess\": \"given\"") != std::string::npos ||
              better.output.find("\"initial_guess\": \"orientations\"") != std::string::npos)
      << better.output;
  const CommandResult given =
      run_command(slam2d("optimize --json --initial given " + input + " --out " + dir.file("given.g2o")));
  ASSERT_EQ(given.exit_code, 0) << given.errors;
  EXPECT_FALSE(json_number(given.output, "estimated_start_chi2").has_value()) << given.output;
  // Optimised from each start, the result is no worse than from either.
  EXPECT_LE(json_number(each.output, "final_chi2").value_or(1e9),
            json_number(given.output, "final_chi2").value_or(-1.0) * (1.0 + 1e-12));
  EXPECT_LE(json_number(each.output, "final_chi2").value_or(1e9),
            json_number(better.output, "final_chi2").value_or(-1.0) * (1.0 + 1e-12));
  const CommandResult bad = run_command(slam2d("optimize --initial nowhere " + input + " --out " + dir.file("bad.g2o")));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.errors.find("nowhere"), std::string::npos) << bad.errors;
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.g2o")));
}

// slam2d spoil: false loop closures after the graph's own edges, the same file from the same seed;
// optimize --robust puts the kernel on the loop edges and says which.
TEST(SpoilCli, AddsFalseClosuresAfterTheGraphsOwnEdges) {
  TempDir dir;
  const std::string input = write_file(dir, "square.g2o", kSquare);
  const std::string out = dir.file("spoiled.g2o");
  const auto spoil = [&](const std::string& to, int seed) {
    return run_command(slam2d("spoil --json --share 0.5 --seed " + std::to_string(seed) + " " + input + " --out " + to));
  };
  const CommandResult result = spoil(out, 7);
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const double loops = json_number(result.output, "loop_edges").value_or(-1.0);
  EXPECT_GE(loops, 1.0);
  EXPECT_EQ(json_number(result.output, "false_edges"), loops);  // half of the loop edges afterwards
  EXPECT_EQ(json_number(result.output, "first_false_edge"), 5.0);
  const PoseGraphFile written = read_pose_graph(out);
  EXPECT_EQ(written.edges.size(), static_cast<std::size_t>(5 + loops));
  EXPECT_EQ(written.vertices.size(), 4u);
  ASSERT_EQ(spoil(dir.file("again.g2o"), 7).exit_code, 0);
  std::ifstream a(out), b(dir.file("again.g2o"));
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), std::string(std::istreambuf_iterator<char>(b), {}));

  const CommandResult robust =
      run_command(slam2d("optimize --json --robust dcs --robust-scale 1 " + out + " --out " + dir.file("robust.g2o")));
  ASSERT_EQ(robust.exit_code, 0) << robust.errors;
  EXPECT_NE(robust.output.find("\"robust\": \"dcs\""), std::string::npos) << robust.output;
  const CommandResult bad = run_command(slam2d("spoil " + input + " --out " + dir.file("spoiled.txt")));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.errors.find(".g2o"), std::string::npos) << bad.errors;
  EXPECT_FALSE(std::filesystem::exists(dir.file("spoiled.txt")));
}

// Three laps of a 10 m x 6 m rectangle, a pose every metre, exact odometry and a loop edge to the
// pose one lap earlier at every third pose.
std::string three_laps() {
  std::vector<std::array<double, 3>> poses;
  for (int k = 0; k < 96; ++k) {
    const int s = k % 32;
    const double drift = 0.1 * (k / 32);  // laps a little apart
    if (s < 10) poses.push_back({s + drift, drift, 0.0});
    else if (s < 16) poses.push_back({10 + drift, s - 10 + drift, M_PI / 2});
    else if (s < 26) poses.push_back({10 - (s - 16) + drift, 6 + drift, M_PI});
    else poses.push_back({drift, 6 - (s - 26) + drift, -M_PI / 2});
  }
  std::ostringstream text;
  text.precision(17);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    text << "VERTEX_SE2 " << k << " " << poses[k][0] << " " << poses[k][1] << " " << poses[k][2] << "\n";
  }
  const auto edge = [&](std::size_t i, std::size_t j) {
    const double c = std::cos(poses[i][2]), s = std::sin(poses[i][2]);
    const double dx = poses[j][0] - poses[i][0], dy = poses[j][1] - poses[i][1];
    text << "EDGE_SE2 " << i << " " << j << " " << c * dx + s * dy << " " << -s * dx + c * dy << " "
         << std::remainder(poses[j][2] - poses[i][2], 2 * M_PI) << " 100 0 0 100 0 400\n";
  };
  for (std::size_t k = 0; k + 1 < poses.size(); ++k) edge(k, k + 1);
  for (std::size_t k = 32; k < poses.size(); k += 3) edge(k - 32, k);
  return text.str();
}

// GNC over the truncated cost (--robust tls) keeps every true loop edge and no false one of a
// graph with a third of its loop edges false; plain least squares keeps them all (precision 0.7);
// the default, least squares behind the consistency gate, keeps the true ones alone.
TEST(OptimizeCli, GraduatedNonConvexityRejectsTheFalseClosures) {
  TempDir dir;
  const std::string input = write_file(dir, "laps.g2o", three_laps());
  const std::string spoiled = dir.file("spoiled.g2o");
  const CommandResult spoil = run_command(slam2d("spoil --json --share 0.3 --seed 3 " + input + " --out " + spoiled));
  ASSERT_EQ(spoil.exit_code, 0) << spoil.errors;
  const double first_false = json_number(spoil.output, "first_false_edge").value_or(-1.0);
  ASSERT_GT(first_false, 0.0);
  const auto optimize = [&](const std::string& robust) {
    return run_command(slam2d("optimize --json " + robust + " --outliers-from " + std::to_string(int(first_false)) +
                              " " + spoiled + " --out " + dir.file("out.g2o")));
  };
  const CommandResult tls = optimize("--robust gnc --robust-scale 1 --gate none");
  ASSERT_EQ(tls.exit_code, 0) << tls.errors;
  EXPECT_EQ(json_number(tls.output, "precision"), 1.0) << tls.output;
  EXPECT_EQ(json_number(tls.output, "recall"), 1.0) << tls.output;
  EXPECT_GE(json_number(tls.output, "gnc_rounds").value_or(0.0), 1.0) << tls.output;
  EXPECT_NE(tls.output.find("\"robust\": \"tls\""), std::string::npos) << tls.output;  // gnc names tls
  const CommandResult plain = optimize("--robust none --gate none");
  ASSERT_EQ(plain.exit_code, 0) << plain.errors;
  EXPECT_LT(json_number(plain.output, "precision").value_or(1.0), 0.8) << plain.output;
  EXPECT_EQ(json_number(plain.output, "recall"), 1.0) << plain.output;
  const CommandResult gated = optimize("");
  ASSERT_EQ(gated.exit_code, 0) << gated.errors;
  EXPECT_EQ(json_number(gated.output, "precision"), 1.0) << gated.output;
  EXPECT_EQ(json_number(gated.output, "recall"), 1.0) << gated.output;
  EXPECT_NE(gated.output.find("\"gate\": \"pairs\""), std::string::npos) << gated.output;
  const CommandResult negative =
      run_command(slam2d("optimize --outliers-from -1 " + spoiled + " --out " + dir.file("negative.g2o")));
  EXPECT_NE(negative.exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(dir.file("negative.g2o")));
}

TEST(OptimizeCli, OutputFormatFollowsTheExtension) {
  TempDir dir;
  const std::string input = write_file(dir, "square.g2o", kSquare);
  const CommandResult toro = run_command(slam2d("optimize --quiet " + input + " --out " + dir.file("square.graph")));
  ASSERT_EQ(toro.exit_code, 0) << toro.errors;
  EXPECT_NE(toro.output.find("final_chi2"), std::string::npos) << toro.output;  // the text summary
  const PoseGraphFile toro_file = read_pose_graph(dir.file("square.graph"));
  EXPECT_EQ(toro_file.format, PoseGraphFormat::kToro);
  EXPECT_EQ(toro_file.vertices.size(), 4u);

  // Compressed output, read back as input (TORO in, g2o out).
  const CommandResult gz = run_command(slam2d("optimize --json " + dir.file("square.graph") + " --out " + dir.file("square.g2o.gz")));
  ASSERT_EQ(gz.exit_code, 0) << gz.errors;
  EXPECT_NE(gz.output.find("\"format\": \"toro\""), std::string::npos) << gz.output;
  EXPECT_EQ(read_pose_graph(dir.file("square.g2o.gz")).format, PoseGraphFormat::kG2o);
}

TEST(OptimizeCli, EdgesOnlyInputGetsVertices) {
  TempDir dir;
  std::string edges_only;
  std::istringstream lines(kSquare);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("EDGE_SE2", 0) == 0) edges_only += line + "\n";
  }
  const std::string input = write_file(dir, "edges.g2o", edges_only);
  const CommandResult result = run_command(slam2d("optimize --json " + input + " --out " + dir.file("out.g2o")));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  EXPECT_EQ(json_number(result.output, "nodes"), 4.0);
  EXPECT_EQ(read_pose_graph(dir.file("out.g2o")).vertices.size(), 4u);
}

TEST(OptimizeCli, BadInputFailsWithoutOutput) {
  TempDir dir;
  struct Case {
    std::string file;
    std::string text;
    std::string prefix;  // expected start of stderr
  };
  const std::string truncated = dir.file("truncated.g2o");
  const std::string bad_number = dir.file("bad_number.g2o");
  const std::string island = dir.file("island.g2o");
  const Case cases[] = {
      {truncated, "VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1\n", truncated + ":2: "},
      {bad_number, "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 x 0 0\n", bad_number + ":2: "},
      {island, "VERTEX_SE2 0 0 0 0\nEDGE_SE2 5 6 1 0 0 1 0 0 1 0 1\n", "pose graph: "},
  };
  for (const Case& bad : cases) {
    write_file(dir, std::filesystem::path(bad.file).filename().string(), bad.text);
    const std::string out = dir.file("out.g2o");
    const CommandResult result = run_command(slam2d("optimize " + bad.file + " --out " + out));
    EXPECT_NE(result.exit_code, 0) << bad.file;
    EXPECT_EQ(result.errors.rfind(bad.prefix, 0), 0u) << result.errors;
    EXPECT_EQ(std::count(result.errors.begin(), result.errors.end(), '\n'), 1) << result.errors;
    EXPECT_FALSE(std::filesystem::exists(out)) << bad.file;
  }
  const std::string good = write_file(dir, "square.g2o", kSquare);
  const CommandResult missing = run_command(slam2d("optimize " + dir.file("missing.g2o") + " --out " + dir.file("out.g2o")));
  EXPECT_NE(missing.exit_code, 0);
  const CommandResult extension = run_command(slam2d("optimize " + good + " --out " + dir.file("out.txt")));
  EXPECT_NE(extension.exit_code, 0);
  EXPECT_NE(extension.errors.find(".g2o"), std::string::npos) << extension.errors;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.txt")));
  const CommandResult iterations = run_command(slam2d("optimize " + good + " --max-iterations 0 --out " + dir.file("out.g2o")));
  EXPECT_NE(iterations.exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.g2o")));
}

}  // namespace
}  // namespace slam2d
