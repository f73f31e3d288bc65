// SPDX-License-Identifier: BSD-3-Clause
#include "interrupt.hpp"

#include <csignal>

namespace slam2d::cli {
namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_signal(int signal) { g_signal = signal; }

}  // namespace

void install_interrupt_handler() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

void check_interrupted(const std::string& what) {
  if (g_signal != 0) {
    throw Interrupted(std::string(g_signal == SIGINT ? "interrupted (SIGINT)" : "terminated (SIGTERM)") + " during " + what +
                      ": stopped cleanly; its outputs were not written (temporary files removed)");
  }
}

}  // namespace slam2d::cli
