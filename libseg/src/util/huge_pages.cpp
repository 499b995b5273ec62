// Per-voxel buffers on 2 MB pages where the system allows it (huge_pages.hpp).
#include "util/huge_pages.hpp"

#include <algorithm>
#include <cstdint>

#include "occseg/parallel.hpp"

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace occseg {

void touch_pages(void* p, std::size_t bytes, int threads) {
  constexpr std::size_t kPage = 4096, kPiece = std::size_t(1) << 21;
  auto* const b = static_cast<volatile unsigned char*>(p);
  parallel_for((bytes + kPiece - 1) / kPiece, threads, [&](std::size_t k0, std::size_t k1) {
    const std::size_t e = std::min(bytes, k1 * kPiece);
    for (std::size_t i = k0 * kPiece; i < e; i += kPage) b[i] = 0;
  });
}

void advise_huge_pages(void* p, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = std::uintptr_t(1) << 21;
  const auto b = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t lo = (b + kHuge - 1) & ~(kHuge - 1), hi = (b + bytes) & ~(kHuge - 1);
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#else
  (void)p;
  (void)bytes;
#endif
}

}  // namespace occseg
