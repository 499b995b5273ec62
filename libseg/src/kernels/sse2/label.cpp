// The labelling's SSE2 kernels (every x86-64 has SSE2): 16 states, or two lanes of a sum, per
// instruction; the tails as the scalar kernels.
#include "kernels/label_levels.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>

namespace occseg::kernels::sse2 {

// Runs of one state are long in real maps: 16 voxels a step.
std::size_t label_find_state(const std::uint8_t* s, std::uint8_t v, std::size_t x, std::size_t e) {
  const __m128i vv = _mm_set1_epi8(static_cast<char>(v));
  while (x + 16 <= e) {
    const auto m = static_cast<unsigned>(
        _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x)), vv)));
    if (m) return x + static_cast<std::size_t>(__builtin_ctz(m));
    x += 16;
  }
  while (x < e && s[x] != v) ++x;
  return x;
}

std::size_t label_find_other(const std::uint8_t* s, std::uint8_t v, std::size_t x, std::size_t e) {
  const __m128i vv = _mm_set1_epi8(static_cast<char>(v));
  while (x + 16 <= e) {
    const unsigned m = ~static_cast<unsigned>(_mm_movemask_epi8(
                           _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x)), vv))) &
                       0xFFFFu;
    if (m) return x + static_cast<std::size_t>(__builtin_ctz(m));
    x += 16;
  }
  while (x < e && s[x] == v) ++x;
  return x;
}

std::size_t label_run_start(const std::uint8_t* s, std::size_t x) {
  const std::uint8_t v = s[x];
  const __m128i vv = _mm_set1_epi8(static_cast<char>(v));
  while (x >= 16) {  // voxels [x - 16, x)
    const auto m = static_cast<unsigned>(_mm_movemask_epi8(
                       _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x - 16)), vv))) ^
                   0xFFFFu;
    if (m) return x - 16 + static_cast<std::size_t>(32 - __builtin_clz(m));  // past the last other state
    x -= 16;
  }
  while (x > 0 && s[x - 1] == v) --x;
  return x;
}

// The differences are summed with SSE2's sum of absolute differences: baseline x86-64 has no
// popcount instruction, and the library call for one is slower.
std::size_t label_count_runs(const std::uint8_t* s, std::size_t rows, std::size_t nx, std::size_t every) {
  std::size_t runs = 0;
  for (std::size_t r = 0; r < rows; r += every) {
    const std::uint8_t* row = s + r * nx;
    runs += 1;
    std::size_t x = 1;
    const __m128i one = _mm_set1_epi8(1), zero = _mm_setzero_si128();
    __m128i acc = zero;
    for (; x + 16 <= nx; x += 16) {  // voxels x .. x + 15 against the ones before them
      const __m128i same = _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x)),
                                          _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x - 1)));
      acc = _mm_add_epi64(acc, _mm_sad_epu8(_mm_andnot_si128(same, one), zero));
    }
    runs += static_cast<std::size_t>(_mm_cvtsi128_si64(acc)) +
            static_cast<std::size_t>(_mm_cvtsi128_si64(_mm_unpackhi_epi64(acc, acc)));
    for (; x < nx; ++x) runs += row[x] != row[x - 1];
  }
  return runs;
}

// Two lanes per instruction, with the roundings of the scalar lanes. Eight chains of dependent
// additions instead of one: a single chain through the map is latency-bound.
double label_run_sum(const float* v, std::size_t n) {
  double l[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  std::size_t k = 0;
  if (n >= 8) {
    __m128d a = _mm_setzero_pd(), b = a, c = a, d = a;  // lanes 0-1, 2-3, 4-5, 6-7
    for (; k + 8 <= n; k += 8) {
      const __m128 lo = _mm_loadu_ps(v + k), hi = _mm_loadu_ps(v + k + 4);
      a = _mm_add_pd(a, _mm_cvtps_pd(lo));
      b = _mm_add_pd(b, _mm_cvtps_pd(_mm_movehl_ps(lo, lo)));
      c = _mm_add_pd(c, _mm_cvtps_pd(hi));
      d = _mm_add_pd(d, _mm_cvtps_pd(_mm_movehl_ps(hi, hi)));
    }
    _mm_storeu_pd(l, a);
    _mm_storeu_pd(l + 2, b);
    _mm_storeu_pd(l + 4, c);
    _mm_storeu_pd(l + 6, d);
  }
  for (; k < n; ++k) l[k & 7] += v[k];
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

}  // namespace occseg::kernels::sse2

#endif
