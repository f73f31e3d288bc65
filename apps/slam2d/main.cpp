// SPDX-License-Identifier: BSD-3-Clause
// slam2d: 2D LiDAR scan matching, localization and SLAM from the command line.

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "commands.hpp"
#include "interrupt.hpp"
#include "slam2d/core/error.hpp"

int main(int argc, char** argv) {
  CLI::App app{"slam2d: 2D LiDAR scan matching, localization and SLAM"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "slam2d 0.1.0");
  slam2d::cli::add_info_command(app);
  slam2d::cli::add_simulate_command(app);
  slam2d::cli::add_map_command(app);
  slam2d::cli::add_eval_command(app);
  slam2d::cli::add_demo_command(app);
  slam2d::cli::add_odometry_command(app);
  slam2d::cli::add_match_bench_command(app);
  slam2d::cli::add_match_command(app);
  slam2d::cli::add_optimize_command(app);
  slam2d::cli::add_spoil_command(app);
  slam2d::cli::add_localize_command(app);
  slam2d::cli::add_perturb_command(app);
  slam2d::cli::add_config_command(app);
  slam2d::cli::add_convert_command(app);
  slam2d::cli::add_fuse_command(app);
  slam2d::cli::add_report_command(app);
  slam2d::cli::install_interrupt_handler();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const slam2d::cli::Interrupted& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 130;
  } catch (const slam2d::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "slam2d: internal error: %s\n", e.what());
    return 2;
  }
  return 0;
}
