// A minimal fork-join loop. Work is split into fixed chunks by index, so what each index computes
// never depends on the thread count.
#pragma once
#include <cstddef>
#include <functional>

namespace occseg {

// Number of worker threads for a `threads` parameter (0: all cores).
int resolve_threads(int threads);

// Calls fn(begin, end) over [0, n) in up to `threads` contiguous chunks, in parallel.
// Exceptions thrown by fn are rethrown in the caller (the first one).
void parallel_for(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& fn);

// Same, for loops whose indices differ in cost (rows of free space are cheap, rows through
// objects are not): [0, n) is cut into up to 8 pieces per thread that threads take from a shared
// counter, so no thread idles while another works through the expensive half of a map. Only for
// loops whose indices are independent: which thread runs which piece varies from run to run.
void parallel_for_dynamic(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& fn);

}  // namespace occseg
