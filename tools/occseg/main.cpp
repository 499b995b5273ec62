// The `occseg` command-line tool: parses arguments, runs one subcommand (`demo` when there is
// none), maps errors to exit codes (0 ok, 1 usage, 2 bad input, 3 internal, 128 + signal when
// interrupted) with a one-line message on stderr. docs/cli.md describes every command.
//
// Out of memory anywhere is exit 3 with "out of memory while <what was being done>", and a
// failed write (of a file or of stdout) exit 2 naming it; the output files stay all or none.
#include <CLI/CLI.hpp>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include "commands.hpp"
#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
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
            << ": stopped; no output file was changed\n";
  return sig ? 128 + sig : kInterrupted;
}

// Memory held back for when an allocation first fails: the new-handler gives it back and throws
// std::bad_alloc, so what runs next (unwinding; destructors that allocate, as nlohmann::json's
// do and which would end the process if that failed; removing the temporaries; the message) has
// memory to work with. Only address space is taken: the pages are never touched.
constexpr std::size_t kReserveBytes = std::size_t(16) << 20;
std::atomic<void*> g_reserve{nullptr};

void release_reserve_and_throw() {
  if (void* r = g_reserve.exchange(nullptr)) ::munmap(r, kReserveBytes);
  throw std::bad_alloc();
}

void hold_memory_reserve() {
  void* r = ::mmap(nullptr, kReserveBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (r != MAP_FAILED) g_reserve = r;
  std::set_new_handler(release_reserve_and_throw);
}

int out_of_memory_exit() {
  char what[200];
  current_activity(what, sizeof what);
  std::fprintf(stderr, "occseg: error: out of memory%s%s\n", *what ? " while " : "", what);
  return kInternal;
}

// The data a command prints is part of its result: a summary that could not be written (a full
// disk, a closed pipe) fails the command with exit 2, as a file that could not be written does.
// std::cout writes through `out` (so the reason of a failed write is kept), which this restores.
int finish_stdout(int rc, FdOutBuf& out, std::streambuf* original) {
  // What a library printed through C stdio goes first, as it was printed first.
  errno = 0;
  int err = std::fflush(stdout) == 0 && !std::ferror(stdout) ? 0 : (errno ? errno : EIO);
  std::cout.flush();
  std::cout.rdbuf(original);
  if (!out.flush_all() && !err) err = out.error() ? out.error() : EIO;
  // Closing tells of errors that some file systems (NFS) report only then. Nothing writes to
  // stdout after this; one that was closed from the start (EBADF) with nothing written is fine.
  if (!err && ::close(STDOUT_FILENO) != 0 && errno != EBADF) err = errno;
  if (!err) return rc;
  std::fprintf(stderr, "occseg: error: cannot write to standard output: %s\n", std::strerror(err));
  return rc == kOk ? kBadInput : rc;
}

int run(int argc, char** argv);

const char* kFooter =
    "Without a subcommand, runs `occseg demo`.\n"
    "Exit codes: 0 ok, 1 usage (bad option or parameter), 2 bad input (missing, unreadable or invalid file)\n"
    "or write error (an output file or stdout), 3 internal error or out of memory, 130 interrupted by Ctrl-C\n"
    "(143: SIGTERM); the output files are replaced all or none.\n";

// The installed documentation: <prefix>/share/doc/occseg beside this program's <prefix>/bin (so a
// moved install still finds its own), else the configured prefix's; a build tree's program
// points at the sources' docs/.
std::string doc_footer() {
  std::string dir;
  char exe[4096];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    exe[n] = '\0';
    std::string d(exe);
    d = d.substr(0, d.find_last_of('/') + 1) + OCCSEG_DOC_DIR_FROM_BIN;
    char real[4096];
    if (::realpath((d + "/README.md").c_str(), real)) dir = std::string(real).substr(0, std::strlen(real) - 10);
  }
  if (dir.empty()) {
    struct stat st {};
    if (::stat(OCCSEG_DOC_DIR "/README.md", &st) == 0) dir = OCCSEG_DOC_DIR;
  }
  if (dir.empty())
    return "Documentation: README.md and docs/ of the occseg sources (installed: <prefix>/share/doc/occseg).\n"
           "Each subcommand has --help.";
  return "Documentation: " + dir + "/README.md and " + dir + "/docs/ (the command: " + dir +
         "/docs/cli.md).\nEach subcommand has --help.";
}

}  // namespace

int main(int argc, char** argv) {
  // Beyond RLIMIT_FSIZE (ulimit -f) a write then fails with EFBIG and is reported as a write
  // error naming the file, instead of SIGXFSZ ending the process and leaving its temporaries.
  std::signal(SIGXFSZ, SIG_IGN);
  hold_memory_reserve();
  FdOutBuf out(STDOUT_FILENO);
  std::streambuf* const original = std::cout.rdbuf(&out);
  int rc;
  try {
    rc = run(argc, argv);
  } catch (const std::bad_alloc&) {
    rc = out_of_memory_exit();
  } catch (const std::length_error&) {
    rc = out_of_memory_exit();
  }
  return finish_stdout(rc, out, original);
}

namespace {

int run(int argc, char** argv) {
  set_activity("loading plugins");
  CLI::App app{"occseg: texture-based segmentation of 3D probabilistic occupancy maps", "occseg"};
  app.set_version_flag("--version", std::string("occseg ") + OCCSEG_VERSION_TEXT);
  app.require_subcommand(0, 1);
  app.footer(std::string(kFooter) + doc_footer());
  // Plugins first, so their parameters, stages and readers show in --help and work in every command.
  load_cli_plugins();
  std::vector<Runner> runners{add_demo(app)};
  runners.push_back(add_segment(app));
  runners.push_back(add_info(app));
  runners.push_back(add_simulate(app));
  runners.push_back(add_evaluate(app));
  runners.push_back(add_figures(app));
  runners.push_back(add_plugins(app));
  set_activity("reading the arguments");
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
  {
    std::string what = "setting up occseg";  // until the command says what it does
    for (const CLI::App* sub : app.get_subcommands()) what += " " + sub->get_name();
    set_activity(what);
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
    return out_of_memory_exit();
  } catch (const std::length_error&) {  // a container asked for more than it can hold
    return out_of_memory_exit();
  } catch (const std::exception& e) {
    if (interrupt_signal()) return interrupted_exit();
    std::cerr << "occseg: internal error: " << one_line(e.what()) << "\n";
    return kInternal;
  }
}

}  // namespace
