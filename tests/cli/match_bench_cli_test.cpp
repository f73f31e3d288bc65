// SPDX-License-Identifier: BSD-3-Clause
// slam2d match-bench (Pomerleau et al. 2013 protocol) on a simulated log whose true trajectory is
// known: the errors in cases.csv are measured against the --reference given (the truth, or a
// deliberately stretched copy of it), a good matcher succeeds at a low perturbation level and
// less as the level grows, the CSV holds pairs x levels x matchers rows, the JSON is valid and
// agrees with it, the same seed gives the same results, raw odometry is labelled as such, and a
// missing or wrong reference or bad --levels stops with a clear error.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::CommandResult;
using test::TempDir;
using test::run_command;

using test::slam2d;

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// One row of cases.csv, by column name.
using CsvRow = std::map<std::string, std::string>;

std::vector<CsvRow> read_csv(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> header;
  std::vector<CsvRow> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    if (header.empty()) {
      header = cells;
      continue;
    }
    EXPECT_EQ(cells.size(), header.size()) << line;
    CsvRow row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

double number(const CsvRow& row, const std::string& column) { return std::stod(row.at(column)); }

// Success rate and mean translation error of one matcher at one level, from the CSV.
struct Cell {
  double success_rate = 0.0;
  double mean_trans_error = 0.0;
  std::size_t cases = 0;
};

Cell cell(const std::vector<CsvRow>& rows, const std::string& matcher, const std::string& level) {
  Cell out;
  for (const CsvRow& row : rows) {
    if (row.at("matcher") != matcher || row.at("level") != level) continue;
    out.success_rate += number(row, "success");
    out.mean_trans_error += number(row, "trans_error");
    ++out.cases;
  }
  if (out.cases > 0) {
    out.success_rate /= static_cast<double>(out.cases);
    out.mean_trans_error /= static_cast<double>(out.cases);
  }
  return out;
}

// The run used by most tests: pl-icp and icp, three levels, 30 pairs.
const char* kLevels = "0.05:2,0.2:10,0.5:20";
const char* kLevelNames[] = {"0.05m_2deg", "0.2m_10deg", "0.5m_20deg"};

CommandResult bench(const test::SimulatedLog& run, const std::string& reference, const std::string& out,
                    const std::string& extra = "") {
  return run_command(slam2d("match-bench " + run.log() + " --reference " + reference +
                            " --matchers pl-icp,icp --levels " + kLevels + " --pairs 30 --quiet --out " + out + " " +
                            extra));
}

// cases.csv without the cpu_us column (the only one that is not a function of the seed).
std::string csv_without_time(const std::string& path) {
  std::string out;
  for (const CsvRow& row : read_csv(path)) {
    for (const auto& [column, value] : row) {
      if (column != "cpu_us") out += column + "=" + value + ";";
    }
    out += "\n";
  }
  return out;
}

TEST(MatchBenchCli, AGoodMatcherSucceedsAtALowLevelAndLessAsTheLevelGrows) {
  TempDir dir;
  const test::SimulatedLog run(40, std::nullopt);  // 40 s of the simulated office (10 Hz scans)
  const CommandResult result = bench(run, run.truth(), dir.file("out"));
  ASSERT_EQ(result.exit_code, 0) << result.errors;
  const std::vector<CsvRow> rows = read_csv(dir.file("out/cases.csv"));
  ASSERT_EQ(rows.size(), 30u * 3u * 2u);  // pairs x levels x matchers
  const Cell easy = cell(rows, "pl-icp", kLevelNames[0]);
  const Cell medium = cell(rows, "pl-icp", kLevelNames[1]);
  const Cell hard = cell(rows, "pl-icp", kLevelNames[2]);
  EXPECT_EQ(easy.cases, 30u);
  EXPECT_GE(easy.success_rate, 0.9);
  EXPECT_LE(medium.success_rate, easy.success_rate);
  EXPECT_LE(hard.success_rate, medium.success_rate);
  EXPECT_LE(hard.success_rate, easy.success_rate - 0.2);
  EXPECT_LT(easy.mean_trans_error, hard.mean_trans_error);
  // The text output says what the reference is, and gives every level.
  EXPECT_NE(result.output.find("reference: trajectory " + run.truth()), std::string::npos) << result.output;
  for (const char* level : kLevelNames) EXPECT_NE(result.output.find(level), std::string::npos) << level;
}

TEST(MatchBenchCli, ErrorsAreMeasuredAgainstTheReferenceGiven) {
  TempDir dir;
  const test::SimulatedLog run(40, std::nullopt);  // 40 s of the simulated office (10 Hz scans)
  ASSERT_EQ(bench(run, run.truth(), dir.file("truth_out")).exit_code, 0);
  const std::vector<CsvRow> rows = read_csv(dir.file("truth_out/cases.csv"));
  ASSERT_FALSE(rows.empty());

  // Every row's true relative pose is the truth's, and its errors are those of its estimate.
  const Trajectory truth = read_trajectory(run.truth());
  const StampIndex index(truth);
  for (const CsvRow& row : rows) {
    const auto target = index.nearest(number(row, "target_stamp"), 1e-6);
    const auto source = index.nearest(number(row, "source_stamp"), 1e-6);
    ASSERT_TRUE(target && source);
    const SE2 T_true = truth[*target].pose.inverse() * truth[*source].pose;  // the simulator's laser sits at the robot's origin
    EXPECT_NEAR(number(row, "true_x"), T_true.x(), 1e-9);
    EXPECT_NEAR(number(row, "true_y"), T_true.y(), 1e-9);
    EXPECT_NEAR(number(row, "true_theta"), T_true.theta(), 1e-9);
    EXPECT_GE((T_true.translation()).norm(), 1.0);  // --distance 1
    const SE2 estimate(number(row, "estimate_x"), number(row, "estimate_y"), number(row, "estimate_theta"));
    const SE2 error = T_true.inverse() * estimate;
    EXPECT_NEAR(number(row, "trans_error"), error.translation().norm(), 1e-9);
    EXPECT_NEAR(number(row, "rot_error_deg"), rad_to_deg(std::abs(normalize_angle(error.theta()))), 1e-7);
    EXPECT_EQ(number(row, "success"),
              (number(row, "trans_error") <= 0.1 && number(row, "rot_error_deg") <= 2.0) ? 1.0 : 0.0);
  }

  // A reference stretched by 15 % moves every true relative pose: the same matches now miss it.
  Trajectory stretched;
  for (const StampedPose& pose : truth) {
    stretched.push_back(pose.stamp, SE2(1.15 * pose.pose.translation(), pose.pose.theta()));
  }
  write_trajectory(dir.file("stretched.txt"), stretched);
  ASSERT_EQ(bench(run, dir.file("stretched.txt"), dir.file("stretched_out")).exit_code, 0);
  const std::vector<CsvRow> stretched_rows = read_csv(dir.file("stretched_out/cases.csv"));
  const Cell honest = cell(rows, "pl-icp", kLevelNames[0]);
  const Cell misled = cell(stretched_rows, "pl-icp", kLevelNames[0]);
  // (15 % of pairs about 0.7 m apart: about 0.1 m; measured 0.100 against 0.0055)
  EXPECT_GT(misled.mean_trans_error, honest.mean_trans_error + 0.05);
  EXPECT_GT(misled.mean_trans_error, 5.0 * honest.mean_trans_error);
  EXPECT_LT(misled.success_rate, honest.success_rate - 0.5);
}

TEST(MatchBenchCli, JsonIsValidAgreesWithTheCsvAndTheSameSeedGivesTheSameResults) {
  TempDir dir;
  const test::SimulatedLog run(40, std::nullopt);  // 40 s of the simulated office (10 Hz scans)
  const CommandResult a = bench(run, run.truth(), dir.file("a"), "--json --seed 4");
  const CommandResult b = bench(run, run.truth(), dir.file("b"), "--seed 4");
  const CommandResult c = bench(run, run.truth(), dir.file("c"), "--seed 5");
  ASSERT_EQ(a.exit_code, 0) << a.errors;
  ASSERT_EQ(b.exit_code, 0) << b.errors;
  ASSERT_EQ(c.exit_code, 0) << c.errors;
  EXPECT_EQ(a.output, file_bytes(dir.file("a/summary.json")));  // --json prints what --out writes
  EXPECT_EQ(csv_without_time(dir.file("a/cases.csv")), csv_without_time(dir.file("b/cases.csv")));
  EXPECT_NE(csv_without_time(dir.file("a/cases.csv")), csv_without_time(dir.file("c/cases.csv")));

  // Valid JSON whose success rates are the CSV's, with the reference stated.
  const std::string check =
      "/usr/bin/python3 -c \"import json, csv, sys\n"
      "s = json.load(open(sys.argv[1]))\n"
      "rows = list(csv.DictReader(open(sys.argv[2])))\n"
      "assert s['reference']['kind'] == 'trajectory' and s['reference']['ground_truth'] is True, s['reference']\n"
      "assert s['pairs'] == 30 and len(s['levels']) == 3, s\n"
      "for level, v in s['levels'].items():\n"
      "  for m, r in v['matchers'].items():\n"
      "    cases = [float(x['success']) for x in rows if x['matcher'] == m and x['level'] == level]\n"
      "    assert len(cases) == 30 and abs(sum(cases) / 30 - r['success_rate']) < 1e-12, (level, m)\n"
      "    assert r['trans_error_p50'] <= r['trans_error_p75'] <= r['trans_error_p95'] <= r['trans_error_max']\n"
      "print('ok')\" " +
      dir.file("a/summary.json") + " " + dir.file("a/cases.csv");
  const CommandResult checked = run_command(check);
  EXPECT_EQ(checked.exit_code, 0) << checked.errors;
  EXPECT_EQ(checked.output, "ok\n");
}

TEST(MatchBenchCli, RawOdometryIsAReferenceOnlyWhenAskedForAndIsLabelled) {
  TempDir dir;
  const test::SimulatedLog run(40, std::nullopt);  // 40 s of the simulated office (10 Hz scans)
  const CommandResult odometry = bench(run, "odometry", dir.file("odo"), "--json");
  ASSERT_EQ(odometry.exit_code, 0) << odometry.errors;
  EXPECT_NE(odometry.output.find("\"kind\": \"odometry\""), std::string::npos) << odometry.output;
  EXPECT_NE(odometry.output.find("\"ground_truth\": false"), std::string::npos) << odometry.output;
  EXPECT_NE(odometry.output.find("RAW ODOMETRY"), std::string::npos);
  const CommandResult text = bench(run, "odometry", dir.file("odo_text"));
  EXPECT_NE(text.output.find("reference: RAW ODOMETRY of " + run.log() + ", not ground truth"), std::string::npos)
      << text.output;
  // The simulated log's scan poses are its odometry: refused as a "corrected" log, by name.
  const CommandResult corrected = bench(run, "corrected", dir.file("corrected"));
  EXPECT_EQ(corrected.exit_code, 1);
  EXPECT_EQ(corrected.errors.rfind(run.log() + ": its scan poses are its odometry", 0), 0u) << corrected.errors;
  EXPECT_FALSE(std::filesystem::exists(dir.file("corrected")));
}

TEST(MatchBenchCli, AMissingOrWrongReferenceAndBadLevelsAreClearErrors) {
  TempDir dir;
  const test::SimulatedLog run(40, std::nullopt);  // 40 s of the simulated office (10 Hz scans)
  // No --reference: no silent default.
  const CommandResult missing = run_command(slam2d("match-bench " + run.log() + " --matchers icp --quiet"));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.errors.find("--reference"), std::string::npos) << missing.errors;
  // A reference file that does not exist is named.
  const CommandResult absent = bench(run, dir.file("nowhere.txt"), dir.file("o1"));
  EXPECT_EQ(absent.exit_code, 1);
  EXPECT_NE(absent.errors.find(dir.file("nowhere.txt")), std::string::npos) << absent.errors;

  const Trajectory truth = read_trajectory(run.truth());
  // Another time base: no scan has a reference pose.
  Trajectory shifted_in_time, first_third;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    shifted_in_time.push_back(truth[i].stamp + 1000.0, truth[i].pose);
    if (3 * i < truth.size()) first_third.push_back(truth[i].stamp, truth[i].pose);
  }
  write_trajectory(dir.file("later.txt"), shifted_in_time);
  write_trajectory(dir.file("third.txt"), first_third);
  const CommandResult later = bench(run, dir.file("later.txt"), dir.file("o2"));
  EXPECT_EQ(later.exit_code, 1);
  EXPECT_EQ(later.errors.rfind(dir.file("later.txt") + ": the reference covers 0 of the", 0), 0u) << later.errors;
  // A reference covering a third of the log is refused under the default --min-coverage 0.5 ...
  const CommandResult third = bench(run, dir.file("third.txt"), dir.file("o3"));
  EXPECT_EQ(third.exit_code, 1);
  EXPECT_NE(third.errors.find("not a reference for this log"), std::string::npos) << third.errors;
  // ... and accepted, with a warning and pairs only among its scans, when asked for.
  const CommandResult allowed = bench(run, dir.file("third.txt"), dir.file("o4"), "--min-coverage 0.3");
  ASSERT_EQ(allowed.exit_code, 0) << allowed.errors;
  EXPECT_NE(allowed.errors.find("warning: the reference covers"), std::string::npos) << allowed.errors;
  const double last_stamp = first_third.back().stamp;
  for (const CsvRow& row : read_csv(dir.file("o4/cases.csv"))) EXPECT_LE(number(row, "source_stamp"), last_stamp);

  for (const char* levels : {"0.1", "a:b", "0.1:-5", "0.1:5,", "0.1:5x", "nan:1", "0.1:5,0.1:5"}) {
    SCOPED_TRACE(levels);
    const CommandResult bad = run_command(slam2d("match-bench " + run.log() + " --reference " + run.truth() +
                                                 " --matchers icp --quiet --levels '" + levels + "' --out " +
                                                 dir.file("o5")));
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.errors.find("--levels"), std::string::npos) << bad.errors;
    EXPECT_FALSE(std::filesystem::exists(dir.file("o5")));
  }
}

TEST(MatchBenchCli, TheCdfScriptDrawsTheCasesAndRefusesOtherFiles) {
  if (run_command("/usr/bin/python3 -c 'import matplotlib, numpy'").exit_code != 0) GTEST_SKIP() << "no python3 with matplotlib";
  TempDir dir;
  const test::SimulatedLog run(40, std::nullopt);  // 40 s of the simulated office (10 Hz scans)
  ASSERT_EQ(bench(run, run.truth(), dir.file("out")).exit_code, 0);
  const CommandResult drawn = run_command("/usr/bin/python3 bench/datasets/match_bench_cdf.py " + dir.file("out/cases.csv") +
                                          " --out " + dir.file("cdf.png") + " --title test");
  ASSERT_EQ(drawn.exit_code, 0) << drawn.errors;
  EXPECT_EQ(file_bytes(dir.file("cdf.png")).substr(1, 3), "PNG");
  const CommandResult refused = run_command("/usr/bin/python3 bench/datasets/match_bench_cdf.py " + run.truth() + " --out " +
                                            dir.file("bad.png"));
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.errors.find(run.truth()), std::string::npos) << refused.errors;
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.png")));
}

}  // namespace
}  // namespace slam2d
