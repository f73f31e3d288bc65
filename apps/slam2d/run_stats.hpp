// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CPU time, wall time and peak memory of the running process, for summaries and benchmarks.

#include <chrono>

namespace slam2d::cli {

class RunClock {
 public:
  RunClock();
  double cpu_seconds() const;   // user + system CPU of this process since construction
  double wall_seconds() const;  // since construction

 private:
  double cpu_start_;
  std::chrono::steady_clock::time_point wall_start_;
};

/// Peak resident set size of this process so far, in MB.
double peak_rss_mb();

}  // namespace slam2d::cli
