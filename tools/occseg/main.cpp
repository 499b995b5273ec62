// The `occseg` command-line tool: parses arguments, runs one subcommand (`demo` when there is
// none), maps errors to exit codes (0 ok, 1 usage, 2 bad input, 3 internal, 128 + signal when
// interrupted) with a one-line message on stderr. docs/cli.md describes every command.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "occseg/error.hpp"
#include "progress.hpp"

using namespace occseg;
using namespace occseg::cli;

namespace {

int exit_code(Status s) {
  switch (s) {
    case Status::invalid_argument: return kUsage;
    case Status::internal: case Status::no_memory: return kInternal;
    default: return kBadInput;
  }
}

// Messages stay on one line, whatever a library put in them.
std::string one_line(std::string m) {
  for (char& c : m)
    if (c == '\n' || c == '\r') c = ' ';
  while (!m.empty() && m.back() == ' ') m.pop_back();
  return m;
}

int interrupted_exit() {
  const int sig = interrupt_signal();
  std::cerr << "occseg: " << (sig == SIGTERM ? "terminated" : "interrupted")
            << ": stopped, and the output files written so far were removed\n";
  return sig ? 128 + sig : kInterrupted;
}

const char* kFooter =
    "Without a subcommand, runs `occseg demo`.\n"
    "Exit codes: 0 ok, 1 usage (bad option or parameter), 2 bad input (missing, unreadable or invalid file),\n"
    "3 internal error, 130 interrupted by Ctrl-C (143: SIGTERM); outputs are written all or none.\n"
    "Documentation: docs/cli.md. Each subcommand has --help.";

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"occseg: texture-based segmentation of 3D probabilistic occupancy maps", "occseg"};
  app.set_version_flag("--version", std::string("occseg ") + OCCSEG_VERSION_TEXT);
  app.require_subcommand(0, 1);
  app.footer(kFooter);
  // Plugins first, so their parameters, stages and readers show in --help and work in every command.
  load_cli_plugins();
  std::vector<Runner> runners{add_demo(app)};
  runners.push_back(add_segment(app));
  runners.push_back(add_info(app));
  runners.push_back(add_simulate(app));
  runners.push_back(add_evaluate(app));
  runners.push_back(add_figures(app));
  runners.push_back(add_plugins(app));
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) args.push_back("demo");
  try {
    std::reverse(args.begin(), args.end());  // CLI11 takes the arguments in reverse order
    app.parse(args);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e) == 0 ? kOk : kUsage;
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e) == 0 ? kOk : kUsage;
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e) == 0 ? kOk : kUsage;
  } catch (const CLI::ParseError& e) {
    std::string help = "occseg";  // point at the help of the subcommand being parsed, if any
    for (const CLI::App* sub : app.get_subcommands()) help += " " + sub->get_name();
    std::cerr << "occseg: usage error: " << one_line(e.what()) << " (see " << help << " --help)\n";
    return kUsage;
  }
  try {
    for (auto& r : runners) {
      const int rc = r();
      if (rc >= 0) return rc;
    }
    // Options but no subcommand (`occseg --threads 2` is not a thing): the demo is only the
    // default of a bare `occseg`.
    std::cerr << "occseg: usage error: no subcommand (see occseg --help)\n";
    return kUsage;
  } catch (const Error& e) {
    if (e.status() == Status::cancelled || interrupt_signal()) return interrupted_exit();
    std::cerr << "occseg: error: " << one_line(e.what()) << "\n";
    return exit_code(e.status());
  } catch (const std::bad_alloc&) {
    std::cerr << "occseg: error: out of memory\n";
    return kInternal;
  } catch (const std::exception& e) {
    if (interrupt_signal()) return interrupted_exit();
    std::cerr << "occseg: internal error: " << one_line(e.what()) << "\n";
    return kInternal;
  }
}
