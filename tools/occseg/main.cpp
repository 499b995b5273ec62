// The `occseg` command-line tool: parses arguments, runs one subcommand, maps errors to exit
// codes (0 ok, 1 usage, 2 bad input, 3 internal) with a one-line message on stderr.
#include <CLI/CLI.hpp>
#include <iostream>
#include <vector>

#include "commands.hpp"
#include "occseg/error.hpp"

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"occseg: texture-based segmentation of 3D probabilistic occupancy maps"};
  app.set_version_flag("--version", std::string("occseg ") + OCCSEG_VERSION_TEXT);
  app.require_subcommand(1);
  std::vector<Runner> runners{add_segment(app)};
  runners.push_back(add_simulate(app));
  runners.push_back(add_evaluate(app));
  runners.push_back(add_figures(app));
  runners.push_back(add_plugins(app));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kOk : kUsage;
  }
  try {
    load_cli_plugins();
    for (auto& r : runners) {
      const int rc = r();
      if (rc >= 0) return rc;
    }
    return kUsage;
  } catch (const Error& e) {
    std::cerr << "occseg: error: " << e.what() << "\n";
    return exit_code(e.status());
  } catch (const std::bad_alloc&) {
    std::cerr << "occseg: error: out of memory\n";
    return kInternal;
  } catch (const std::exception& e) {
    std::cerr << "occseg: internal error: " << e.what() << "\n";
    return kInternal;
  }
}
