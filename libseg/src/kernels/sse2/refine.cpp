// The refinement's kernels in SSE2 (kernels/refine.hpp), 16 voxels per step: the x86-64 baseline.
#include "kernels/generic/refine_loops.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>

#include "kernels/sse2/bit_rows.hpp"

namespace occseg::kernels::sse2 {

using generic::kFree;
using generic::kFreeXorOccupied;
using generic::kUnknown;

std::size_t next_boundary(const std::uint8_t* st, std::size_t k, std::size_t len, int step) {
  const __m128i two = _mm_set1_epi8(kFreeXorOccupied);
  while (k + 16 <= len) {
    // memory span of scan positions [k, k + 16): forward j = k..k+15, backward j = len-k-16..len-1-k
    const std::size_t j0 = step > 0 ? k : len - k - 16;
    const std::size_t b0 = step > 0 ? j0 - 1 : j0 + 1;
    const __m128i x = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(st + j0)),
                                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(st + b0)));
    const auto m = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(x, two)));
    if (m)
      return step > 0 ? k + static_cast<std::size_t>(__builtin_ctz(m))
                      : k + 15 - static_cast<std::size_t>(31 - __builtin_clz(m));
    k += 16;
  }
  return generic::next_boundary_from(st, k, len, step);
}

std::size_t window_starts(const std::uint8_t* prev, const std::uint8_t* cur, std::uint8_t* skip, std::size_t nx,
                          std::uint32_t* lanes) {
  const __m128i two = _mm_set1_epi8(kFreeXorOccupied), zero = _mm_setzero_si128(), one = _mm_set1_epi8(1);
  std::size_t x = 0, count = 0;
  for (; x + 16 <= nx; x += 16) {
    const __m128i p = _mm_loadu_si128(reinterpret_cast<const __m128i*>(prev + x));
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(cur + x));
    const __m128i sk = _mm_loadu_si128(reinterpret_cast<const __m128i*>(skip + x));
    const __m128i start = _mm_and_si128(_mm_cmpeq_epi8(_mm_xor_si128(p, c), two), _mm_cmpeq_epi8(sk, zero));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(skip + x), _mm_subs_epu8(sk, one));
    for (auto m = static_cast<unsigned>(_mm_movemask_epi8(start)); m; m &= m - 1)
      lanes[count++] = static_cast<std::uint32_t>(x + static_cast<std::size_t>(__builtin_ctz(m)));
  }
  return generic::window_starts_from(prev, cur, skip, x, nx, lanes, count);
}

PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                   std::size_t nx, const word_t* const* occ, const word_t* const* unk) {
  PlaneRow r;
  const auto starts = [&](std::size_t b, std::size_t e, std::uint32_t* lanes) {
    const std::size_t count = window_starts(prev + b, cur + b, skip + b, e - b, lanes);
    for (std::size_t j = 0; j < count; ++j) lanes[j] += static_cast<std::uint32_t>(b);
    return count;
  };
  generic::lane_windows(prev, cur, rs, rows, skip, 0, nx, occ, unk, starts, r);
  return r;
}

void pack_states(const std::uint8_t* st, std::size_t nx, word_t* unknown, word_t* free) {
  generic::clear_words(unknown, nx);
  generic::clear_words(free, nx);
  const __m128i u = _mm_set1_epi8(static_cast<char>(kUnknown)), f = _mm_set1_epi8(static_cast<char>(kFree));
  std::size_t x = 0;
  for (; x + 16 <= nx; x += 16) {
    const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(st + x));
    detail::set_bits16(unknown, x, _mm_cmpeq_epi8(s, u));
    detail::set_bits16(free, x, _mm_cmpeq_epi8(s, f));
  }
  generic::pack_states_from(st, x, nx, unknown, free);
}

void unpack_unknown(const word_t* w, std::size_t nx, std::uint8_t* st) {
  const __m128i unknown = _mm_set1_epi8(static_cast<char>(kUnknown));
  std::size_t x = 0;
  for (; x + 16 <= nx; x += 16) {
    const __m128i set = detail::bytes_of_bits16(w, x);
    __m128i* p = reinterpret_cast<__m128i*>(st + x);
    _mm_storeu_si128(p, _mm_or_si128(_mm_and_si128(set, unknown), _mm_andnot_si128(set, _mm_loadu_si128(p))));
  }
  generic::unpack_unknown_from(w, x, nx, st);
}

}  // namespace occseg::kernels::sse2
#endif
