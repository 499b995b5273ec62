// The labelling's SSE2 kernels (every x86-64 has SSE2): 16 states, or two lanes of a sum, per
// instruction; the tails as the scalar kernels.
#include "kernels/label_levels.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>

namespace occseg::kernels::sse2 {

// 16 voxels a step, whose run-start bits are two whole bytes once the bit index is a multiple
// of 8 (the voxels before that one by one); voxel 0 of the row is compared with the shifted copy
// of its own vector (and set), the last few voxels are a vector ending on the row's last voxel.
void label_row_starts(const std::uint8_t* row, std::size_t nx, std::uint8_t* bits, std::size_t i0) {
  const auto set = [&](std::size_t x) {
    bits[(i0 + x) / 8] = static_cast<std::uint8_t>(bits[(i0 + x) / 8] | (1u << ((i0 + x) % 8)));
  };
  // Bits of voxels t .. t + 15 (t + 16 <= nx): where a voxel differs from the one before it.
  const auto starts16 = [&](std::size_t t) -> unsigned {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + t));
    const __m128i before = t ? _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + t - 1)) : _mm_slli_si128(v, 1);
    return (~static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(v, before))) & 0xFFFFu) | (t ? 0u : 1u);
  };
  std::size_t x = 0;
  if (i0 % 8 || nx < 16) {
    set(0);
    for (x = 1; x < nx && (nx < 16 || (i0 + x) % 8); ++x)
      if (row[x] != row[x - 1]) set(x);
  }
  for (; x + 16 <= nx; x += 16) {
    const unsigned m = starts16(x);
    std::uint8_t* b = bits + (i0 + x) / 8;
    b[0] = static_cast<std::uint8_t>(b[0] | (m & 0xFFu));
    b[1] = static_cast<std::uint8_t>(b[1] | (m >> 8));
  }
  if (x < nx) {  // 1 to 15 voxels from a whole byte on
    const unsigned m = starts16(nx - 16) >> (x - (nx - 16));
    std::uint8_t* b = bits + (i0 + x) / 8;
    b[0] = static_cast<std::uint8_t>(b[0] | (m & 0xFFu));
    if (nx - x > 8) b[1] = static_cast<std::uint8_t>(b[1] | (m >> 8));
  }
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
