// Internal link between occseg::parallel_for and occseg::Context: the context installed on the
// calling thread (by Context::run) takes the parallel loops made on that thread.
#pragma once
#include <cstddef>
#include <functional>

namespace occseg {

class Context;

// Installs `context` (or none, nullptr) on this thread for the scope's lifetime.
class PoolScope {
 public:
  explicit PoolScope(Context* context);
  ~PoolScope();
  PoolScope(const PoolScope&) = delete;
  PoolScope& operator=(const PoolScope&) = delete;

 private:
  Context* saved_;
};

// True when a context is installed on this thread (parallel loops go to its pool).
bool pool_installed();

// Runs fn over [0, n) in min(threads, context threads, n) chunks on the context's pool.
void run_on_pool(Context* context, std::size_t n, int threads,
                 const std::function<void(std::size_t, std::size_t)>& fn);

}  // namespace occseg
