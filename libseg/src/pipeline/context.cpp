// occseg::Context: the caller-owned thread pool and recycled results (context.hpp).
#include "occseg/context.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "util/parallel_pool.hpp"
#include "pipeline/segment_internal.hpp"

namespace occseg {

// Spins for up to kSpin while `ready` is false, then gives up (the caller then blocks on a
// condition variable). A segmentation makes about 20 parallel loops in a row with short serial
// parts between them; a worker blocked in the kernel took 30-50 us to wake for each, as long as
// starting a thread, where spinning picks the next loop up within a microsecond (OpenMP runtimes
// spin likewise before they sleep).
template <class Ready>
bool spin_until(Ready&& ready) {
  constexpr auto kSpin = std::chrono::microseconds(100);
  const auto until = std::chrono::steady_clock::now() + kSpin;
  for (unsigned i = 1;; ++i) {
    if (ready()) return true;
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
    if (i % 64 == 0 && std::chrono::steady_clock::now() > until) return false;
  }
}

// Workers wait (spin, then sleep on `wake`) until the generation changes, run their chunk of the
// current job, and count down `pending`; the caller runs chunk 0 and waits for pending == 0. The
// fields are written under `m`; `generation`, `stop` and `pending` are atomic only so that the
// spinning reads them without the lock.
struct Context::Pool {
  std::mutex call;  // one job at a time
  std::mutex m;
  std::condition_variable wake, done;
  std::vector<std::thread> workers;
  const std::function<void(std::size_t, std::size_t)>* fn = nullptr;
  std::size_t n = 0, chunks = 0;
  std::atomic<std::size_t> pending{0};
  std::atomic<std::uint64_t> generation{0};
  std::atomic<bool> stop{false};
  std::exception_ptr first;
  std::mutex spare_mutex;
  LabelArray spare_labels;  // from recycle(), for the next segment()
  Workspace spare_workspace;  // from the last segment()

  void work(std::size_t k) {
    std::uint64_t seen = 0;
    for (;;) {
      spin_until([&] { return stop.load(std::memory_order_acquire) || generation.load(std::memory_order_acquire) != seen; });
      std::unique_lock<std::mutex> lock(m);
      wake.wait(lock, [&] { return stop || generation != seen; });
      if (stop) return;
      seen = generation;
      if (k >= chunks) continue;  // this job has fewer chunks than workers
      const auto* f = fn;
      const std::size_t b = n * k / chunks, e = n * (k + 1) / chunks;
      lock.unlock();
      try {
        (*f)(b, e);
      } catch (...) {
        std::lock_guard<std::mutex> g(m);
        if (!first) first = std::current_exception();
      }
      std::lock_guard<std::mutex> g(m);
      if (--pending == 0) done.notify_one();
    }
  }

  // Same chunks as occseg::parallel_for with t = chunks: chunk k is [n k / t, n (k + 1) / t).
  void run(std::size_t count, std::size_t t, const std::function<void(std::size_t, std::size_t)>& f) {
    std::lock_guard<std::mutex> serial(call);
    {
      std::lock_guard<std::mutex> lock(m);
      fn = &f;
      n = count;
      chunks = t;
      pending = t - 1;
      first = nullptr;
      ++generation;
    }
    wake.notify_all();
    std::exception_ptr mine;
    try {
      // A nested parallel_for inside chunk 0 must not wait for this (busy) pool.
      const PoolScope none(nullptr);
      f(0, count / t);
    } catch (...) {
      mine = std::current_exception();
    }
    spin_until([&] { return pending.load(std::memory_order_acquire) == 0; });
    std::unique_lock<std::mutex> lock(m);
    done.wait(lock, [&] { return pending == 0; });
    fn = nullptr;
    if (mine) std::rethrow_exception(mine);
    if (first) std::rethrow_exception(first);
  }
};

Context::Context(int threads) : pool_(std::make_unique<Pool>()) {
  if (threads < 0)
    throw Error(Status::invalid_argument, "context threads = " + std::to_string(threads) + " is negative");
  const int t = resolve_threads(threads);
  try {
    for (int k = 1; k < t; ++k) pool_->workers.emplace_back([p = pool_.get(), k] { p->work(static_cast<std::size_t>(k)); });
  } catch (const std::system_error&) {
    // Fewer threads than asked: the pool works with those it has.
  }
}

Context::~Context() {
  {
    std::lock_guard<std::mutex> lock(pool_->m);
    pool_->stop = true;
  }
  pool_->wake.notify_all();
  for (auto& th : pool_->workers) th.join();
}

int Context::threads() const { return static_cast<int>(pool_->workers.size()) + 1; }

void Context::recycle(Result&& result) {
  LabelArray labels = std::move(result.labels);
  result = Result();
  std::lock_guard<std::mutex> lock(pool_->spare_mutex);
  pool_->spare_labels.swap(labels);  // the older array, if any, is freed outside the lock
}

void Context::parallel_for(std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) {
  run_on_pool(this, n, threads(), fn);
}

void Context::run(const std::function<void()>& fn) {
  const PoolScope scope(this);
  fn();
}

// Called by occseg::parallel_for while a context is installed on this thread.
void run_on_pool(Context* context, std::size_t n, int threads,
                 const std::function<void(std::size_t, std::size_t)>& fn) {
  if (n == 0) return;
  std::size_t t = static_cast<std::size_t>(std::min(resolve_threads(threads), context->threads()));
  if (t > n) t = n;
  if (t <= 1) {
    fn(0, n);
    return;
  }
  context->pool_->run(n, t, fn);
}

Result segment(Context& context, const Grid& grid, const Params& params, bool keep_stages) {
  LabelArray labels;
  Workspace workspace;
  {
    std::lock_guard<std::mutex> lock(context.pool_->spare_mutex);
    labels.swap(context.pool_->spare_labels);
    std::swap(workspace, context.pool_->spare_workspace);
  }
  Result r;
  context.run([&] { r = segment_into(grid, params, keep_stages, std::move(labels), &workspace); });
  std::lock_guard<std::mutex> lock(context.pool_->spare_mutex);
  std::swap(context.pool_->spare_workspace, workspace);  // a concurrent call's, if any, is freed
  return r;
}

void insert_scan(Context& context, OccupancyFusion& fusion, const Vec3& sensor, const float* xyz, std::size_t count,
                 std::size_t stride_floats, int threads) {
  context.run([&] { fusion.insert_scan(sensor, xyz, count, stride_floats, threads); });
}

}  // namespace occseg
