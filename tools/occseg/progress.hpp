// Progress bar on stderr and Ctrl-C for long jobs of the `occseg` tool. The library reports
// progress through callbacks (Params::progress, ScanOptions::progress, ScanConfig::progress);
// the callbacks made here draw the bar and return false once the user pressed Ctrl-C, so the
// library stops at its next report and throws Error(cancelled).
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace occseg::cli {

// Installs handlers for SIGINT and SIGTERM that only record the signal (async-signal-safe); the
// job notices it at its next progress report or check_interrupted(). Only commands that check
// install them; in the others a signal ends the process as usual.
void install_interrupt_handlers();
// The signal received (SIGINT, SIGTERM) or 0.
int interrupt_signal();
// Throws Error(cancelled) when a signal was received.
void check_interrupted();

// What the command is doing now ("reading map.npy", "segmenting: refinement", "writing
// labels.npy"), for the message when memory runs out. ProgressBar::update records its label
// here too. Copies into a fixed buffer (truncating), so it allocates nothing and cannot fail;
// thread-safe.
void set_activity(const char* what) noexcept;
inline void set_activity(const std::string& what) noexcept { set_activity(what.c_str()); }
// The last activity recorded ("" when none), copied into `out` of `size` bytes.
void current_activity(char* out, std::size_t size) noexcept;

// True when stderr is a terminal (isatty).
bool stderr_is_terminal();

class ProgressBar {
 public:
  // Draws only when `enabled` (the commands pass: stderr is a terminal and not --quiet) and the
  // job has lasted longer than `delay_seconds` since construction, so short jobs stay silent.
  // A ticker thread redraws the last reported state ten times a second, so the bar appears on
  // time and its clock runs during steps that report nothing (reading a file, writing).
  explicit ProgressBar(bool enabled, double delay_seconds = default_delay());
  // 0.5 s, or the environment variable OCCSEG_PROGRESS_DELAY (seconds, >= 0) when it is set.
  static double default_delay();
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // Shows `fraction` (0..1) of the phase `label` ("segmenting: refinement"); returns false once a
  // signal was received. Thread-safe.
  bool update(const std::string& label, double fraction);
  // Callback for Params::progress: the five stages mapped onto one bar, weighted by their usual
  // share of the time.
  std::function<bool(const char* stage, double fraction)> segment_callback();
  // Callback for ScanOptions::progress and ScanConfig::progress, under `label`.
  std::function<bool(double fraction)> callback(const std::string& label);
  // Erases the bar, if drawn, and keeps it away until the next update (before printing to the
  // terminal, and at the end).
  void clear();
  double elapsed() const;

 private:
  void draw_locked();  // with mutex_ held
  void tick();
  std::atomic<bool> enabled_;
  double delay_;
  std::chrono::steady_clock::time_point start_;
  std::string label_;         // the last reported state...
  double fraction_ = 0;
  bool active_ = false;       // ...shown until clear()
  std::string drawn_label_;
  int drawn_percent_ = -1;
  int fd_ = -1;               // a duplicate of stderr, taken at construction
  bool drawn_ = false;
  bool stop_ = false;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread ticker_;
};

}  // namespace occseg::cli
