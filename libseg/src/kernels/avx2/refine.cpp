// The refinement's kernels in AVX2 (kernels/refine.hpp), 32 voxels per step.
#include "kernels/generic/refine_loops.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/avx2/bit_rows.hpp"

namespace occseg::kernels::avx2 {

using generic::kFree;
using generic::kUnknown;

// The plain loops, vectorised by the compiler for AVX2.
__attribute__((target("avx2"))) bool any_boundary(const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  return generic::any_boundary(a, b, n);
}

__attribute__((target("avx2"))) bool any_occupied(const std::uint8_t* s, std::size_t n) {
  return generic::any_occupied(s, n);
}

// Self-contained (a call into the baseline SSE2 loop from here made the growth twice as slow).
__attribute__((target("avx2"))) void pack_states(const std::uint8_t* st, std::size_t nx, word_t* unknown,
                                                 word_t* free) {
  generic::clear_words(unknown, nx);
  generic::clear_words(free, nx);
  const __m256i u = _mm256_set1_epi8(static_cast<char>(kUnknown)), f = _mm256_set1_epi8(static_cast<char>(kFree));
  std::size_t x = 0;
  for (; x + 32 <= nx; x += 32) {
    const __m256i s = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(st + x));
    detail::set_bits32(unknown, x, _mm256_cmpeq_epi8(s, u));
    detail::set_bits32(free, x, _mm256_cmpeq_epi8(s, f));
  }
  generic::pack_states_from(st, x, nx, unknown, free);
}

// Four cells (read as one 4-byte word: all in the row) per step.
__attribute__((target("avx2"))) void write_cells_row(const std::uint8_t* cs, const word_t* w, std::size_t nx,
                                                     std::uint8_t* st) {
  // byte i of a 128-bit half takes cell i / 8 of the four (the low half cells 0, 1; the high 2, 3)
  const __m256i pick =
      _mm256_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3);
  const __m256i unknown = _mm256_set1_epi8(static_cast<char>(kUnknown));
  std::size_t x = 0;
  for (; x + 32 <= nx; x += 32) {
    std::uint32_t four;
    std::memcpy(&four, cs + x / 8, 4);
    const __m256i cells = _mm256_shuffle_epi8(_mm256_set1_epi32(static_cast<int>(four)), pick);
    const __m256i v = _mm256_blendv_epi8(cells, unknown, detail::bytes_of_bits32(w, x));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(st + x), v);
  }
  if (x < nx) generic::write_cells_row_from(cs, w, x, nx, st);
}

}  // namespace occseg::kernels::avx2
#endif
