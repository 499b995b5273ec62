// Per-voxel buffers on 2 MB pages (internal). A 320 x 320 x 128 map's label array is 52 MB:
// 12,800 page faults of 4 KB, or 26 of 2 MB; the faults were a quarter of the labelling stage.
#pragma once
#include <cstddef>
#include <vector>

namespace occseg {

// Asks the kernel to back [p, p + bytes) with 2 MB pages where it can (Linux transparent huge
// pages in "madvise" mode, the Debian default). Only the whole 2 MB pages inside the range are
// advised. A hint: does nothing elsewhere or when refused. Call before the first touch.
void advise_huge_pages(void* p, std::size_t bytes);

// Writes a zero byte into every 4 KB page of [p, p + bytes), the pages split over `threads`: fresh
// pages are faulted in (and zeroed by the kernel) in parallel instead of by whichever stage
// touches them first. The contents are garbage afterwards (scratch only).
void touch_pages(void* p, std::size_t bytes, int threads);

// v.resize(n), with fresh storage advised before the new elements are written (or, for an
// UninitVector, before the stages first touch them).
template <class T, class A>
void resize_huge(std::vector<T, A>& v, std::size_t n) {
  if (v.capacity() < n) {
    std::vector<T, A> fresh;
    fresh.reserve(n);
    advise_huge_pages(fresh.data(), n * sizeof(T));
    fresh.assign(v.begin(), v.end());
    v.swap(fresh);
  }
  v.resize(n);
}

}  // namespace occseg
