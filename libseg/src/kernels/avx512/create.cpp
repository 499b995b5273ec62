// The create kernels in AVX-512 F (kernels/create.hpp).
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/create_impl.hpp"

namespace occseg::kernels::avx512 {

// (GCC 12 warns inside its own AVX-512 intrinsics, whose pass-through operands are deliberately
// undefined.)
#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// avx2::add_cells with the eight cells' sums in one register of eight doubles, and each pair of
// additions' floats (voxels i and i + 1 of the eight cells) picked out of the 64 loaded floats by
// two two-register permutes and a blend instead of the 8 x 8 transpose: fewer instructions, the
// same additions in the same order. The last cells % 8 go to scalar::add_cells.
__attribute__((target("avx512f"))) void add_cells(const float* v, double* sums, std::size_t cells) {
  __m512i ia[4], ib[4];  // pair q: voxels 2q (lanes 0-7) and 2q + 1 (lanes 8-15)
  for (int q = 0; q < 4; ++q) {
    alignas(64) std::int32_t a[16] = {}, b[16] = {};
    for (int j = 0; j < 4; ++j) {
      a[j] = 8 * j + 2 * q;           // cell j (of registers 0-1): lanes 0-3
      a[8 + j] = 8 * j + 2 * q + 1;   // lanes 8-11
      b[4 + j] = 8 * j + 2 * q;       // cell 4 + j (of registers 2-3): lanes 4-7
      b[12 + j] = 8 * j + 2 * q + 1;  // lanes 12-15
    }
    ia[q] = _mm512_load_si512(a);
    ib[q] = _mm512_load_si512(b);
  }
  std::size_t k = 0;
  for (; k + 8 <= cells; k += 8, v += 64) {
    const __m512 z0 = _mm512_loadu_ps(v), z1 = _mm512_loadu_ps(v + 16);       // cells 0-1, 2-3
    const __m512 z2 = _mm512_loadu_ps(v + 32), z3 = _mm512_loadu_ps(v + 48);  // cells 4-5, 6-7
    __m512d acc = _mm512_loadu_pd(sums + k);
    for (int q = 0; q < 4; ++q) {
      const __m512 w = _mm512_mask_blend_ps(0xF0F0, _mm512_permutex2var_ps(z0, ia[q], z1),
                                            _mm512_permutex2var_ps(z2, ib[q], z3));
      acc = _mm512_add_pd(acc, _mm512_cvtps_pd(_mm512_castps512_ps256(w)));
      acc = _mm512_add_pd(acc, _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(w), 1))));
    }
    _mm512_storeu_pd(sums + k, acc);
  }
  if (k < cells) scalar::add_cells(v, sums + k, cells - k);
}
#pragma GCC diagnostic pop

// avx2::own_bits with compares into mask registers, 16 voxels each.
__attribute__((target("avx512f"))) void own_bits(const float* p, std::size_t n, float lo, float hi, word_t* u,
                                                 word_t* o) {
  const __m512 l = _mm512_set1_ps(lo), h = _mm512_set1_ps(hi);
  std::size_t i = 0;
  for (; i + 64 <= n; i += 64) {
    std::uint64_t uw = 0, ow = 0;
    for (int j = 0; j < 4; ++j) {
      const __m512 a = _mm512_loadu_ps(p + i + 16 * j);
      const __mmask16 in = _mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(a, l, _CMP_NLT_UQ), a, h, _CMP_NGT_UQ);
      uw |= static_cast<std::uint64_t>(in) << (16 * j);
      ow |= static_cast<std::uint64_t>(_mm512_cmp_ps_mask(a, h, _CMP_GT_OQ)) << (16 * j);
    }
    u[i / 64] = uw;
    o[i / 64] = ow;
  }
  if (i < n) scalar::own_bits(p + i, n - i, lo, hi, u + i / 64, o + i / 64);
}

}  // namespace occseg::kernels::avx512
#endif
