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

namespace {
__attribute__((target("avx2"))) inline std::uint32_t mask(__m256i v) {
  return static_cast<std::uint32_t>(_mm256_movemask_epi8(v));
}
__attribute__((target("avx2"))) inline __m256i load(const std::uint8_t* q) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q));
}
__attribute__((target("avx2"))) inline void store(std::uint8_t* q, __m256i v) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(q), v);
}
}  // namespace

// A plane scan's row 32 lanes at a time, every window of them at once (as kernels/avx512/refine.cpp
// does 64: a block of 32 lanes is half a word of each window row's own-state bits); the lanes past
// the last whole block one by one.
__attribute__((target("avx2"))) PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs,
                                                   int rows, std::uint8_t* skip, std::size_t nx,
                                                   const word_t* const* occ, const word_t* const* unk) {
  const __m256i boundary = _mm256_set1_epi8(generic::kFreeXorOccupied), free = _mm256_set1_epi8(kFree);
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi8(1);
  PlaneRow r;
  std::size_t x = 0;
  for (; x + 32 <= nx; x += 32) {
    const __m256i p = load(prev + x), c = load(cur + x), sk = load(skip + x);
    const std::uint32_t start =
        mask(_mm256_and_si256(_mm256_cmpeq_epi8(_mm256_xor_si256(p, c), boundary), _mm256_cmpeq_epi8(sk, zero)));
    __m256i next = _mm256_subs_epu8(sk, one);  // every other lane counts down
    if (start) {
      r.started = true;
      const std::size_t i = x / 64;
      const unsigned b = x % 64;
      const std::uint32_t from_free = start & mask(_mm256_cmpeq_epi8(p, free)), from_occupied = start & ~from_free;
      std::uint32_t in[64], into_side[64];
      std::uint32_t any_from = 0, any_into = 0, held = start;
      __m256i length = zero;  // the window's voxels less one
      int w = 0;
      for (; w < rows && held; ++w) {
        if (w > 0) {
          held &= mask(_mm256_cmpeq_epi8(load(cur + w * rs + x), c));
          if (!held) break;
          length = _mm256_add_epi8(length, _mm256_and_si256(detail::bytes_of_mask32(held), one));
        }
        const auto o = static_cast<std::uint32_t>(occ[w][i] >> b);
        const std::uint32_t u = static_cast<std::uint32_t>(unk[w][i] >> b) & ~o, f = ~o & ~u;
        in[w] = held;
        into_side[w] = (from_free & o) | (from_occupied & f);
        any_from |= held & ((from_free & f) | (from_occupied & o));
        any_into |= held & into_side[w];
      }
      for (int k = 0; k < w; ++k) {
        const std::uint32_t moves = in[k] & any_from & ~(any_into & into_side[k]);
        if (!moves) continue;
        std::uint8_t* const row = cur + k * rs + x;
        store(row, _mm256_blendv_epi8(load(row), p, detail::bytes_of_mask32(moves)));
        if (moves & from_occupied) r.occupied_rows |= std::uint64_t{1} << k;
      }
      next = _mm256_blendv_epi8(next, length, detail::bytes_of_mask32(start));
    }
    store(skip + x, next);
  }
  generic::lane_windows(prev, cur, rs, rows, skip, x, nx, occ, unk, generic::PlainStarts{prev, cur, skip}, r);
  return r;
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
