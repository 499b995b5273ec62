// A caller-owned execution context: a small persistent thread pool that the library's
// parallel loops use for calls made through it, instead of starting threads on every call.
// No global state: each Context is independent, and calls without one behave as before.
#pragma once
#include <cstddef>
#include <functional>
#include <memory>

#include "occseg/fusion.hpp"
#include "occseg/segment.hpp"

namespace occseg {

class Context {
 public:
  // Starts threads - 1 worker threads (threads = 0: all cores). Throws Error(invalid_argument)
  // for a negative count; if the system refuses a thread, the pool is simply smaller.
  explicit Context(int threads = 0);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Threads that work on a call: the workers plus the calling thread.
  int threads() const;

  // Hands a result the caller is done with back to the context: the next segment(context, ...)
  // writes its labels into this result's label array instead of allocating and paging in 4 bytes
  // per voxel of fresh memory (whose pages the kernel zeroes: about 8 % of a call on a
  // 320 x 320 x 128 map, docs/performance.md). `result` is left empty. The context keeps one array, the last one
  // handed back, until a call takes it (a map with more voxels than it holds gets fresh memory)
  // or the context is destroyed: 4 bytes per voxel held between calls. The call that takes it
  // uses it for its scratch and its labels, so that call's peak is a plain call's.
  void recycle(Result&& result);

  // parallel_for over this context's threads (same chunks as the free parallel_for with the
  // same count). Exceptions thrown by fn are rethrown here (the first one). One call at a time
  // per context; calls from several threads are serialised.
  void parallel_for(std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn);

  // Runs fn with this context installed on the calling thread: every occseg::parallel_for that
  // fn makes on this thread (segment(), OccupancyFusion::insert_scan, ...) uses the pool, with
  // min(its `threads`, threads()) threads. Nested parallel loops inside a pool task start their
  // own threads as before.
  void run(const std::function<void()>& fn);

  struct Pool;

 private:
  friend void run_on_pool(Context*, std::size_t, int, const std::function<void(std::size_t, std::size_t)>&);
  friend Result segment(Context&, const Grid&, const Params&, bool);
  std::unique_ptr<Pool> pool_;
};

// segment() with its parallel loops on the context's threads. Same result as segment().
Result segment(Context& context, const Grid& grid, const Params& params = Params::defaults(),
               bool keep_stages = false);

// OccupancyFusion::insert_scan with its parallel loops on the context's threads. Same grid.
void insert_scan(Context& context, OccupancyFusion& fusion, const Vec3& sensor, const float* xyz, std::size_t count,
                 std::size_t stride_floats, int threads = 0);

}  // namespace occseg
