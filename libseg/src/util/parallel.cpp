// parallel_for and parallel_for_dynamic: on the calling thread's context when one is installed,
// else on threads of their own.
#include "occseg/parallel.hpp"

#include "util/parallel_pool.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace occseg {

namespace {
// The context a caller installed on this thread with Context::run (none by default).
thread_local Context* installed = nullptr;
}  // namespace

bool pool_installed() { return installed != nullptr; }

PoolScope::PoolScope(Context* context) : saved_(installed) { installed = context; }
PoolScope::~PoolScope() { installed = saved_; }

int resolve_threads(int threads) {
  if (threads > 0) return threads;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw ? static_cast<int>(hw) : 1;
}

void parallel_for(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& fn) {
  if (n == 0) return;
  if (installed) {  // a caller's pool instead of new threads
    run_on_pool(installed, n, threads, fn);
    return;
  }
  std::size_t t = static_cast<std::size_t>(resolve_threads(threads));
  if (t > n) t = n;
  if (t <= 1) {
    fn(0, n);
    return;
  }
  std::exception_ptr first;
  std::mutex m;
  auto run = [&](std::size_t b, std::size_t e) {
    try {
      fn(b, e);
    } catch (...) {
      std::lock_guard<std::mutex> lock(m);
      if (!first) first = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(t - 1);
  // A thread that cannot be started (no memory for its stack, a process limit) is not an
  // error: its chunk runs here instead. Chunks stay the same, so results do too.
  std::size_t started = 1;
  try {
    for (; started < t; ++started) pool.emplace_back(run, n * started / t, n * (started + 1) / t);
  } catch (const std::system_error&) {
  }
  run(0, n / t);
  for (std::size_t k = started; k < t; ++k) run(n * k / t, n * (k + 1) / t);
  for (auto& th : pool) th.join();
  if (first) std::rethrow_exception(first);
}

void parallel_for_dynamic(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& fn) {
  if (n == 0) return;
  const std::size_t t = std::min(n, static_cast<std::size_t>(resolve_threads(threads)));
  const std::size_t pieces = std::min(n, 8 * t);
  std::atomic<std::size_t> next{0};
  parallel_for(t, threads, [&](std::size_t, std::size_t) {
    for (std::size_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < pieces;)
      fn(n * k / pieces, n * (k + 1) / pieces);
  });
}

}  // namespace occseg
