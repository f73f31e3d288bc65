// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The slam2d subcommands. Each add_*_command registers its options on the app and the action
// to run; actions throw slam2d::Error on bad input and main() turns that into a message and exit 1.

#include <CLI/CLI.hpp>

namespace slam2d::cli {

void add_info_command(CLI::App& app);
void add_simulate_command(CLI::App& app);
void add_map_command(CLI::App& app);
void add_eval_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_odometry_command(CLI::App& app);
void add_match_bench_command(CLI::App& app);
void add_match_command(CLI::App& app);
void add_optimize_command(CLI::App& app);
void add_spoil_command(CLI::App& app);
void add_localize_command(CLI::App& app);
void add_perturb_command(CLI::App& app);
void add_config_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_fuse_command(CLI::App& app);
void add_report_command(CLI::App& app);

}  // namespace slam2d::cli
