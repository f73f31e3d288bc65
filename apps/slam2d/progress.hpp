// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Progress line on stderr for long runs: shown only on a terminal, not with --quiet, and only once
// a run has lasted half a second; redrawn at most ten times a second.

#include <chrono>
#include <string>

namespace slam2d::cli {

class Progress {
 public:
  Progress(std::string label, bool quiet);
  ~Progress();
  /// fraction in [0, 1] (negative: unknown); detail is free text such as "5234 scans".
  void update(double fraction, const std::string& detail);
  /// Clears the line.
  void finish();

 private:
  std::string label_;
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace slam2d::cli
