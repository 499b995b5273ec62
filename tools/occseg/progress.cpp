#include "progress.hpp"

#include <pthread.h>
#include <fcntl.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "occseg/error.hpp"

namespace occseg::cli {

namespace {

volatile std::sig_atomic_t g_signal = 0;

std::mutex g_activity_mutex;
char g_activity[160] = "";

extern "C" void on_signal(int sig) {
  if (!g_signal) g_signal = sig;
}

int terminal_width() {
  winsize w{};
  if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col >= 20) return w.ws_col;
  return 80;
}

// Share of the segmentation time each stage usually takes (measured on the simulated scenes),
// so the bar moves evenly; the order is segment()'s.
struct StageWeight {
  const char* name;
  double weight;
};
constexpr StageWeight kStages[] = {
    {"texture", 0.25}, {"division", 0.20}, {"creation", 0.10}, {"refinement", 0.30}, {"labelling", 0.15}};

}  // namespace

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  // No SA_RESTART: a call that blocks (a plugin's reader on a pipe, a write to a stdout nobody
  // reads) returns EINTR and fails, so Ctrl-C or SIGTERM ends it instead of being swallowed by a
  // restart; every other job stops at its next check of the flag. Reads and writes of regular
  // files are never interrupted by a signal, so they are unaffected.
  sa.sa_flags = 0;
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
}

int interrupt_signal() { return g_signal; }

void check_interrupted() {
  if (g_signal)
    throw Error(Status::cancelled, g_signal == SIGINT ? "interrupted (Ctrl-C)" : "terminated by a signal");
}

void set_activity(const char* what) noexcept {
  std::lock_guard<std::mutex> lock(g_activity_mutex);
  std::snprintf(g_activity, sizeof g_activity, "%s", what ? what : "");
}

void current_activity(char* out, std::size_t size) noexcept {
  if (!size) return;
  std::lock_guard<std::mutex> lock(g_activity_mutex);
  std::snprintf(out, size, "%s", g_activity);
}

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

double ProgressBar::default_delay() {
  const char* e = std::getenv("OCCSEG_PROGRESS_DELAY");
  if (!e || !*e) return 0.5;
  char* end = nullptr;
  const double v = std::strtod(e, &end);
  return end && *end == '\0' && v >= 0 && v < 1e6 ? v : 0.5;
}

ProgressBar::ProgressBar(bool enabled, double delay)
    : enabled_(enabled), delay_(delay), start_(std::chrono::steady_clock::now()) {
  // The terminal as it is now: readers that silence a library's chatter (OctoMap's) point fd 2
  // at /dev/null for a while, and the bar must still reach the terminal then.
  if (enabled_) fd_ = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
  if (fd_ < 0) enabled_ = false;
  if (enabled_) ticker_ = std::thread([this] { tick(); });
}

ProgressBar::~ProgressBar() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
  clear();
  if (fd_ >= 0) ::close(fd_);
}

double ProgressBar::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressBar::tick() {
  // Signals go to the main thread, which defers Ctrl-C while it puts the output files in place.
  sigset_t all;
  sigfillset(&all);
  ::pthread_sigmask(SIG_BLOCK, &all, nullptr);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    wake_.wait_for(lock, std::chrono::milliseconds(100));
    try {
      if (!stop_ && active_ && elapsed() >= delay_) draw_locked();
    } catch (const std::exception&) {
      // Out of memory for the line: no bar this time (an exception leaving this thread would
      // end the process).
    }
  }
}

bool ProgressBar::update(const std::string& label, double fraction) {
  set_activity(label);
  if (g_signal) return false;
  if (!enabled_) return true;
  std::lock_guard<std::mutex> lock(mutex_);
  label_ = label;
  fraction_ = fraction;
  active_ = true;
  // A new phase, or a new whole percent of it, shows at once (so a phase that ends between two
  // ticks still shows how far it got: at most 101 lines per phase); otherwise the ticker redraws
  // ten times a second, for the clock.
  const int percent = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 100 + 0.5);
  if ((label != drawn_label_ || percent != drawn_percent_) && elapsed() >= delay_) draw_locked();
  return !g_signal;
}

void ProgressBar::draw_locked() {
  if (!enabled_) return;
  const double seconds = elapsed();
  const double fraction = std::clamp(fraction_, 0.0, 1.0);
  const int width = 30, filled = static_cast<int>(fraction * width + 0.5);
  char tail[48];
  std::snprintf(tail, sizeof tail, "] %3d%%  %.1f s", static_cast<int>(fraction * 100 + 0.5), seconds);
  std::string line = "occseg: " + label_ + " [" + std::string(filled, '#') + std::string(width - filled, '.') + tail;
  const std::size_t max = static_cast<std::size_t>(terminal_width() - 1);
  if (line.size() > max) line.resize(max);
  line = "\r" + line + "\033[K";
  if (::write(fd_, line.data(), line.size()) < 0) enabled_ = false;
  drawn_ = true;
  drawn_label_ = label_;
  drawn_percent_ = static_cast<int>(fraction * 100 + 0.5);
}

void ProgressBar::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  active_ = false;
  drawn_label_.clear();
  if (!drawn_) return;
  static const char erase[] = "\r\033[K";
  if (::write(fd_, erase, sizeof erase - 1) < 0) enabled_ = false;
  drawn_ = false;
}

std::function<bool(const char*, double)> ProgressBar::segment_callback() {
  return [this](const char* stage, double fraction) {
    double before = 0, weight = 0;
    for (const StageWeight& s : kStages) {
      if (std::strcmp(s.name, stage) == 0) {
        weight = s.weight;
        break;
      }
      before += s.weight;
    }
    if (weight == 0) before = 0;  // a stage this table does not know: show it on its own
    return update(std::string("segmenting: ") + stage, weight ? before + weight * fraction : fraction);
  };
}

std::function<bool(double)> ProgressBar::callback(const std::string& label) {
  return [this, label](double fraction) { return update(label, fraction); };
}

}  // namespace occseg::cli
