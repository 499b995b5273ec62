// The process's idle thread pools (shared_pools.hpp).
#include "pipeline/shared_pools.hpp"

#include <mutex>
#include <utility>
#include <vector>

#include <pthread.h>

#include "occseg/context.hpp"
#include "occseg/parallel.hpp"

namespace occseg::detail {

namespace {

// Idle pools, each used by no call. Destroyed at exit (their idle threads joined), so that leak
// checkers see every thread ended.
class IdlePools {
 public:
  static IdlePools& get() {
    static IdlePools pools;  // thread-safe initialisation
    return pools;
  }

  std::unique_ptr<Context> take(int threads) {
    {
      std::lock_guard<std::mutex> lock(m_);
      for (auto it = idle_.begin(); it != idle_.end(); ++it)
        if ((*it)->threads() >= threads) {
          std::unique_ptr<Context> c = std::move(*it);
          idle_.erase(it);
          return c;
        }
    }
    return std::make_unique<Context>(threads);
  }

  void give(std::unique_ptr<Context> c) {
    std::unique_ptr<Context> dropped;  // joined outside the lock
    std::lock_guard<std::mutex> lock(m_);
    if (idle_.size() < kKeep) idle_.push_back(std::move(c));
    else dropped = std::move(c);
  }

 private:
  // More idle pools than calls that ran at once would never be used; beyond a few, a program
  // with many segmenting threads starts pools as before.
  static constexpr std::size_t kKeep = 4;

  IdlePools() { pthread_atfork(&prepare, &parent, &child); }

  // fork() copies the pools but not their threads: the child must never run a call on them (it
  // would wait for workers that do not exist), nor join them. The lock is held across fork() so
  // that the child's copy is in a known state.
  static void prepare() { get().m_.lock(); }
  static void parent() { get().m_.unlock(); }
  static void child() {
    IdlePools& p = get();
    // Abandoned, never destroyed (their threads are not in this process), and kept reachable so
    // that a leak checker at the child's exit does not report them.
    static auto* abandoned = new std::vector<Context*>();
    try {
      for (auto& c : p.idle_) abandoned->push_back(c.get());
    } catch (...) {
      // Out of memory in the child: the rest are abandoned unlisted.
    }
    for (auto& c : p.idle_) static_cast<void>(c.release());
    p.idle_.clear();
    p.m_.unlock();
  }

  std::mutex m_;
  std::vector<std::unique_ptr<Context>> idle_;
};

}  // namespace

PoolLease::PoolLease(int threads) : pool_(IdlePools::get().take(resolve_threads(threads))) {}

PoolLease::~PoolLease() {
  try {
    IdlePools::get().give(std::move(pool_));
  } catch (...) {
    // Only a vector that cannot grow (out of memory) throws: the pool is then simply stopped.
  }
}

}  // namespace occseg::detail
