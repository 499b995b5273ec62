// The division's plain loops (internal to kernels/): compiled as they are in scalar/ and, inlined
// into functions with the target("avx2") attribute, in avx2/, so that both are table entries.
// Internal linkage: each kernel file has its own copy, compiled for its own instruction set, and
// the linker never picks one file's copy for another's calls.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/divide.hpp"
#include "occseg/texture_codes.hpp"
#include "util/thread_scratch.hpp"

namespace occseg::kernels::generic {
namespace {

// Voxels [x, end) of a row into h one by one (SkipNone: kNoTexture voxels not counted): the whole
// of the scalar counting, and the tails of the vector kernels.
template <bool SkipNone>
[[gnu::always_inline]] inline void count_run(const code_t* row, std::uint32_t x, std::uint32_t end, std::uint32_t* h) {
  for (; x < end; ++x)
    if (!SkipNone || row[x] != kNoTexture) ++h[row[x]];
}

// Calls count(in.codes, in.dims, in.b, bins, h, common, second) of the counting kernel template
// `Kernel` with its two flags as template arguments (SkipNone: in.may_lack_texture; Second: a
// second hint differing from the first): the dispatch every vector counting kernel shares.
template <template <bool, bool> class Kernel>
[[gnu::always_inline]] inline void count_with_hints(const BlockCodes& in, std::size_t bins, std::uint32_t* h) {
  const bool second = in.second != in.common;
  if (in.may_lack_texture) {
    if (second)
      Kernel<true, true>::count(in.codes, in.dims, in.b, bins, h, in.common, in.second);
    else
      Kernel<true, false>::count(in.codes, in.dims, in.b, bins, h, in.common, in.common);
  } else {
    if (second)
      Kernel<false, true>::count(in.codes, in.dims, in.b, bins, h, in.common, in.second);
    else
      Kernel<false, false>::count(in.codes, in.dims, in.b, bins, h, in.common, in.common);
  }
}

// Per-thread room for the codes a packing kernel lists (at least n of them).
inline std::uint16_t* code_list(std::size_t n) {
  thread_local detail::ThreadScratch<std::uint16_t> storage;
  if (storage.size() < n) storage.resize(n);
  return storage.data();
}

// The listed codes, and `same` voxels of the common one, into h (SkipNone: a common kNoTexture is
// not counted).
template <bool SkipNone>
[[gnu::always_inline]] inline void add_listed(std::uint32_t* h, const std::uint16_t* list, std::size_t len,
                                              code_t common, std::uint64_t same) {
  for (std::size_t i = 0; i < len; ++i) ++h[list[i]];
  if (!SkipNone || common != kNoTexture) h[common] += static_cast<std::uint32_t>(same);
}

// Integer counts: any order of the additions gives the same sums, so the compiler may vectorise.
[[gnu::always_inline]] inline std::uint64_t total(const std::uint32_t* h, std::size_t n) {
  std::uint64_t s = 0;
  for (std::size_t i = 0; i < n; ++i) s += h[i];
  return s;
}

// One pass, h written once (a copy and seven passes of h += load and store h seven times more).
[[gnu::always_inline]] inline void sum_eight(std::uint32_t* __restrict h, const std::uint32_t* __restrict a,
                                             std::size_t stride, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    h[i] = ((a[i] + a[stride + i]) + (a[2 * stride + i] + a[3 * stride + i])) +
           ((a[4 * stride + i] + a[5 * stride + i]) + (a[6 * stride + i] + a[7 * stride + i]));
}

[[gnu::always_inline]] inline void add_counts(std::uint32_t* __restrict h, const std::uint32_t* __restrict a,
                                              std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) h[i] += a[i];
}

}  // namespace
}  // namespace occseg::kernels::generic
