// SPDX-License-Identifier: BSD-3-Clause
#include "bench_data.hpp"

#include <cstdlib>
#include <filesystem>
#include <map>
#include <variant>

#include "slam2d/io/carmen.hpp"

namespace slam2d::bench {

const std::vector<LoggedScan>& logged_scans(const std::string& log, std::size_t count) {
  static std::map<std::string, std::vector<LoggedScan>> cache;
  auto [it, inserted] = cache.try_emplace(log);
  if (!inserted) return it->second;
  const char* data = std::getenv("SLAM2D_DATA");
  const std::filesystem::path path = std::filesystem::path(data ? data : "../shared/data") / log / (log + ".clf.gz");
  if (!std::filesystem::exists(path)) return it->second;
  CarmenReader reader(path.string());
  while (it->second.size() < count) {
    auto message = reader.next();
    if (!message) break;
    if (const auto* laser = std::get_if<LaserMessage>(&*message); laser && laser->type != "RLASER") {
      it->second.push_back({laser->scan, laser->odom_pose, laser->laser_pose});
    }
  }
  return it->second;
}

PointCloud2 sensor_cloud(const LaserScan& scan) { return to_point_cloud(scan, ScanFrame::kSensor).cloud; }

const ConsecutivePairs& consecutive_pairs(const std::string& log, std::size_t count) {
  static std::map<std::string, ConsecutivePairs> cache;
  auto [it, inserted] = cache.try_emplace(log);
  if (!inserted) return it->second;
  const auto& scans = logged_scans(log, count);
  for (const auto& s : scans) it->second.clouds.push_back(sensor_cloud(s.scan));
  for (std::size_t i = 0; i + 1 < scans.size(); ++i) {
    const SE2 T_odom_sensor_i = scans[i].odom_pose * scans[i].scan.T_robot_sensor;
    const SE2 T_odom_sensor_j = scans[i + 1].odom_pose * scans[i + 1].scan.T_robot_sensor;
    it->second.guesses.push_back(T_odom_sensor_i.inverse() * T_odom_sensor_j);
  }
  return it->second;
}

void run_consecutive_matches(benchmark::State& state, const Matcher& match, const std::string& log) {
  const ConsecutivePairs& pairs = consecutive_pairs(log);
  if (pairs.guesses.empty()) {
    state.SkipWithError(("log " + log + " not found (set SLAM2D_DATA)").c_str());
    return;
  }
  std::size_t i = 0;
  double matches = 0.0;
  double iterations = 0.0;
  double converged = 0.0;
  for (auto _ : state) {
    const MatchResult result = match(pairs.clouds[i], pairs.clouds[i + 1], pairs.guesses[i]);
    benchmark::DoNotOptimize(result);
    matches += 1.0;
    iterations += result.iterations;
    converged += result.converged ? 1.0 : 0.0;
    i = (i + 1) % pairs.guesses.size();
  }
  // kIsRate | kInvert: CPU seconds per unit of the value; 1e-6 per match makes it microseconds.
  state.counters["us_per_match"] =
      benchmark::Counter(matches * 1e-6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["iterations"] = iterations / matches;
  state.counters["converged"] = converged / matches;
}

}  // namespace slam2d::bench
