// SPDX-License-Identifier: BSD-3-Clause
#include "run_stats.hpp"

#include <sys/resource.h>

namespace slam2d::cli {

namespace {
double process_cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}
}  // namespace

RunClock::RunClock() : cpu_start_(process_cpu_seconds()), wall_start_(std::chrono::steady_clock::now()) {}

double RunClock::cpu_seconds() const { return process_cpu_seconds() - cpu_start_; }

double RunClock::wall_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

}  // namespace slam2d::cli
