// SPDX-License-Identifier: BSD-3-Clause
// slam2d perturb: faults from the command line on a simulated log: the JSON summary counts what
// changed, the same seed gives the same bytes and another seed other bytes, gzip output, the
// geometry read back by `slam2d info`, and bad specs exit 1 with a reason and no output file.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::json_number;
using test::run_command;

using test::slam2d;

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}


TEST(PerturbCli, StallSummaryCountsTheWindows) {
  TempDir dir;
  const test::SimulatedLog simulated(40, std::nullopt);  // the office: FLASER at 10 Hz, ODOM at 20 Hz, stamps from 0
  const std::string log = simulated.log();
  const std::string out = dir.file("stalled.clf");
  const CommandResult result =
      run_command(slam2d("perturb " + log + " --out " + out + " --fault stall:every=10,duration=1.2 --fault decimate:k=2 --seed 3 --json"));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  EXPECT_EQ(json_number(result.output, "stalls"), 4.0);  // windows at 10, 20, 30 and 40 s (the last scan)
  EXPECT_GT(json_number(result.output, "odometry_poses_frozen").value_or(0.0), 3.0 * 30.0);
  EXPECT_NE(result.output.find("\"spec\": \"stall:every=10,start=10,duration=1.2\""), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("\"spec\": \"decimate:k=2\""), std::string::npos) << result.output;
  EXPECT_EQ(json_number(result.output, "laser_lines_removed"), 200.0);  // 401 scans -> 201
  const CommandResult info = run_command(slam2d("info --json " + out));
  ASSERT_EQ(info.exit_code, 0) << info.errors;
  EXPECT_EQ(json_number(info.output, "scans"), 201.0);
}

TEST(PerturbCli, SameSeedSameBytesOtherSeedOtherBytes) {
  TempDir dir;
  const test::SimulatedLog simulated(40, std::nullopt);  // the office: FLASER at 10 Hz, ODOM at 20 Hz, stamps from 0
  const std::string log = simulated.log();
  const std::string faults = " --fault range-noise:sigma=0.02 --fault jitter --quiet";
  for (const char* name : {"a.clf", "b.clf"}) {
    const CommandResult result = run_command(slam2d("perturb " + log + " --out " + dir.file(name) + faults + " --seed 5"));
    ASSERT_EQ(result.exit_code, 0) << result.errors;
    EXPECT_TRUE(result.output.empty()) << result.output;  // --quiet
  }
  ASSERT_EQ(run_command(slam2d("perturb " + log + " --out " + dir.file("c.clf") + faults + " --seed 6")).exit_code, 0);
  EXPECT_EQ(file_bytes(dir.file("a.clf")), file_bytes(dir.file("b.clf")));
  EXPECT_NE(file_bytes(dir.file("a.clf")), file_bytes(dir.file("c.clf")));
}

TEST(PerturbCli, GzipOutputAndGeometryReadBack) {
  TempDir dir;
  const test::SimulatedLog simulated(40, std::nullopt);  // the office: FLASER at 10 Hz, ODOM at 20 Hz, stamps from 0
  const std::string log = simulated.log();
  const std::string out = dir.file("short.clf.gz");
  const CommandResult result =
      run_command(slam2d("perturb " + log + " --out " + out + " --fault beams:k=2 --fault range-max:max=5.6 --quiet"));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const std::string bytes = file_bytes(out);
  ASSERT_GE(bytes.size(), 2u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0x1f);
  EXPECT_EQ(static_cast<unsigned char>(bytes[1]), 0x8b);
  const CommandResult info = run_command(slam2d("info --json " + out));
  ASSERT_EQ(info.exit_code, 0) << info.errors;
  EXPECT_EQ(json_number(info.output, "beams"), 90.0);
  EXPECT_EQ(json_number(info.output, "range_max"), 5.6);
  EXPECT_LE(json_number(info.output, "max_range").value_or(99.0), 5.6);
  EXPECT_NEAR(json_number(info.output, "fov_deg").value_or(0.0), 180.0, 1e-9);
}

TEST(PerturbCli, ScanRateOdomShiftAndGlassFromTheCommandLine) {
  TempDir dir;
  const test::SimulatedLog simulated(40, std::nullopt);  // the office: FLASER at 10 Hz, ODOM at 20 Hz, stamps from 0
  const std::string out = dir.file("slow.clf");
  const CommandResult result = run_command(slam2d("perturb " + simulated.log() + " --out " + out +
                                                  " --fault odom-shift:by=-0.3 --fault scan-rate:hz=2 --fault glass --json"));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  for (const char* spec : {"odom-shift:by=-0.3", "scan-rate:hz=2", "glass:sectors=2,width=30"}) {
    EXPECT_NE(result.output.find("\"spec\": \"" + std::string(spec) + "\""), std::string::npos) << result.output;
  }
  EXPECT_EQ(json_number(result.output, "laser_lines_removed"), 320.0);  // 401 scans at 0, 0.1, ..., 40 s -> every 0.5 s
  EXPECT_GT(json_number(result.output, "odometry_poses_shifted").value_or(0.0), 400.0);
  const CommandResult info = run_command(slam2d("info --json " + out));
  ASSERT_EQ(info.exit_code, 0) << info.errors;
  EXPECT_EQ(json_number(info.output, "scans"), 81.0);
  // A far return the scanner cannot give: its range is 30 m.
  const CommandResult far = run_command(slam2d("perturb " + simulated.log() + " --out " + out + "2 --fault spurious-far:min=40,max=60 --quiet"));
  EXPECT_EQ(far.exit_code, 1);
  EXPECT_NE(far.errors.find("spurious-far: min=40 m is not below the maximum range 30 m"), std::string::npos) << far.errors;
  EXPECT_FALSE(std::filesystem::exists(out + "2"));
}

TEST(PerturbCli, BadSpecsExitOneWithAReasonAndNoOutput) {
  TempDir dir;
  const test::SimulatedLog simulated(40, std::nullopt);  // the office: FLASER at 10 Hz, ODOM at 20 Hz, stamps from 0
  const std::string log = simulated.log();
  const std::string out = dir.file("never.clf");
  for (const std::string& spec : {std::string("wobble"), std::string("stall:lenght=2"), std::string("stall:every=x"),
                                  std::string("duplicate:p=2"), std::string("decimate:k=0.5")}) {
    const CommandResult result = run_command(slam2d("perturb " + log + " --out " + out + " --fault " + spec + " --quiet"));
    EXPECT_EQ(result.exit_code, 1) << spec;
    EXPECT_NE(result.errors.find("--fault '" + spec + "'"), std::string::npos) << result.errors;
    EXPECT_FALSE(std::filesystem::exists(out)) << spec;
  }
  // A fault that cannot apply to this log: its scanner reaches 30 m.
  const CommandResult longer = run_command(slam2d("perturb " + log + " --out " + out + " --fault range-max:max=50 --quiet"));
  EXPECT_EQ(longer.exit_code, 1);
  EXPECT_NE(longer.errors.find("beyond the maximum range"), std::string::npos) << longer.errors;
  EXPECT_FALSE(std::filesystem::exists(out));
  // A missing input names the path.
  const CommandResult missing = run_command(slam2d("perturb " + dir.file("none.clf") + " --out " + out + " --fault stall"));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.errors.find("none.clf"), std::string::npos) << missing.errors;
}

}  // namespace
}  // namespace slam2d
