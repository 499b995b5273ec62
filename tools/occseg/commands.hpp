// Subcommands of the `occseg` tool. Each registers itself on the CLI11 app and returns the
// callback state main() runs after parsing.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>

namespace occseg::cli {

// Exit codes, documented in docs/cli.md. A job stopped by a signal exits with 128 + the signal
// number (130 for Ctrl-C, 143 for SIGTERM), having removed the outputs it had written.
enum Exit { kOk = 0, kUsage = 1, kBadInput = 2, kInternal = 3, kInterrupted = 130 };

using Runner = std::function<int()>;

Runner add_segment(CLI::App& app);
Runner add_demo(CLI::App& app);
Runner add_info(CLI::App& app);
Runner add_simulate(CLI::App& app);
Runner add_evaluate(CLI::App& app);
Runner add_figures(CLI::App& app);
Runner add_plugins(CLI::App& app);

// Registers the built-in readers and writers (plugin builtin_io), then loads the plugins of the
// search path (OCCSEG_PLUGIN_PATH, <libdir>/occseg/plugins) so their stages, readers and
// parameters work in every command; failures are warnings on stderr.
void load_cli_plugins();

}  // namespace occseg::cli
