// SPDX-License-Identifier: BSD-3-Clause
// slam2d config list|dump NAME|table NAME|docs: the settings of every method and matcher, from
// their field tables (core/config_fields.hpp). `dump` prints a preset with the defaults, which
// `map --config`, `localize --config` and `--matcher` read back; `docs` prints
// docs/configuration.md.

#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "slam2d/methods/matcher_registry.hpp"
#include "slam2d/methods/method_presets.hpp"

namespace slam2d::cli {

void add_config_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand("config", "The settings of every method and matcher: defaults, units, ranges");
  command->require_subcommand(1);
  command->add_subcommand("list", "The methods and matchers with settings")->callback([] {
    for (const std::string& name : configurable_names()) std::printf("%s\n", name.c_str());
  });
  auto name = std::make_shared<std::string>();
  CLI::App* dump = command->add_subcommand("dump", "A preset file with the defaults of METHOD (or matcher), commented");
  dump->add_option("name", *name, "A method (hector, graph, rbpf, mcl, ekf, markov, hybrid) or a matcher")->required();
  dump->callback([name] { std::fputs(default_preset(*name).c_str(), stdout); });
  CLI::App* table = command->add_subcommand("table", "The Markdown table of METHOD's (or a matcher's) settings");
  table->add_option("name", *name, "A method or a matcher")->required();
  table->callback([name] { std::fputs(config_table(*name).c_str(), stdout); });
  command->add_subcommand("docs", "docs/configuration.md: every method's and matcher's table")->callback([] {
    std::fputs(configuration_docs().c_str(), stdout);
  });
}

}  // namespace slam2d::cli
