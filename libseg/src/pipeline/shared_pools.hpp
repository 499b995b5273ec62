// Idle thread pools shared by the calls of a process that come without a caller's context.
#pragma once
#include <memory>

namespace occseg {
class Context;
}

namespace occseg::detail {

// A pool of at least resolve_threads(threads) threads for one call, taken from the process's
// idle pools (or made if none is idle), and handed back when the lease ends. A pool serves one
// call at a time, so concurrent calls each get their own: the lease changes nothing about thread
// safety, only that worker threads outlive a call. A few idle pools are kept (their threads
// blocked, using no processor time) until the process exits; in a child made by fork(), whose
// copies of the parent's pools have no threads, they are abandoned and new ones made.
class PoolLease {
 public:
  explicit PoolLease(int threads);
  ~PoolLease();
  PoolLease(const PoolLease&) = delete;
  PoolLease& operator=(const PoolLease&) = delete;
  Context& context() { return *pool_; }

 private:
  std::unique_ptr<Context> pool_;
};

}  // namespace occseg::detail
