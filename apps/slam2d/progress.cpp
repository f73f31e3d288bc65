// SPDX-License-Identifier: BSD-3-Clause
#include "progress.hpp"

#include <unistd.h>

#include <cstdio>

#include "interrupt.hpp"

namespace slam2d::cli {

Progress::Progress(std::string label, bool quiet)
    : label_(std::move(label)),
      enabled_(!quiet && isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(double fraction, const std::string& detail) {
  check_interrupted(label_);
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < 0.5 || now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  shown_ = true;
  if (fraction >= 0.0) {
    std::fprintf(stderr, "\r\033[K%s %3.0f%%  %s  %.1f s", label_.c_str(), 100.0 * fraction, detail.c_str(), elapsed);
  } else {
    std::fprintf(stderr, "\r\033[K%s  %s  %.1f s", label_.c_str(), detail.c_str(), elapsed);
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (!shown_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  shown_ = false;
}

}  // namespace slam2d::cli
