// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A clean stop on SIGINT and SIGTERM: the handler only sets a flag; every long loop already
// updates a Progress line, and Progress::update throws Interrupted when the flag is set, so the
// run unwinds, each unfinished atomic output removes its temporary file, and main() says that
// nothing of the interrupted step was written. Outputs already committed stay as they are.

#include <string>

#include "slam2d/core/error.hpp"

namespace slam2d::cli {

class Interrupted : public Error {
 public:
  using Error::Error;
};

/// Installs the handler (the CLI's main(); the Python module leaves SIGINT to Python).
void install_interrupt_handler();
/// Throws Interrupted naming `what` when a SIGINT or SIGTERM has arrived.
void check_interrupted(const std::string& what);

}  // namespace slam2d::cli
