// The create kernels in AVX2 (kernels/create.hpp).
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/create_impl.hpp"

namespace occseg::kernels::avx2 {

// Eight cells at a time, their 8 x 8 floats transposed so that lane k holds cell k, then
// converted and added in double, four lanes per register: the same additions as scalar::add_cells
// in the same order, so the same sums. The last cells % 8 go to scalar::add_cells.
__attribute__((target("avx2"))) void add_cells(const float* v, double* sums, std::size_t cells) {
  std::size_t k = 0;
  for (; k + 8 <= cells; k += 8, v += 64) {
    __m256 r[8];
    for (int j = 0; j < 8; ++j) r[j] = _mm256_loadu_ps(v + 8 * j);  // r[j][i] = cell j, voxel i
    // 8 x 8 transpose: t[i][j] = r[j][i].
    const __m256 a0 = _mm256_unpacklo_ps(r[0], r[1]), a1 = _mm256_unpackhi_ps(r[0], r[1]);
    const __m256 a2 = _mm256_unpacklo_ps(r[2], r[3]), a3 = _mm256_unpackhi_ps(r[2], r[3]);
    const __m256 a4 = _mm256_unpacklo_ps(r[4], r[5]), a5 = _mm256_unpackhi_ps(r[4], r[5]);
    const __m256 a6 = _mm256_unpacklo_ps(r[6], r[7]), a7 = _mm256_unpackhi_ps(r[6], r[7]);
    const __m256 b0 = _mm256_shuffle_ps(a0, a2, 0x44), b1 = _mm256_shuffle_ps(a0, a2, 0xEE);
    const __m256 b2 = _mm256_shuffle_ps(a1, a3, 0x44), b3 = _mm256_shuffle_ps(a1, a3, 0xEE);
    const __m256 b4 = _mm256_shuffle_ps(a4, a6, 0x44), b5 = _mm256_shuffle_ps(a4, a6, 0xEE);
    const __m256 b6 = _mm256_shuffle_ps(a5, a7, 0x44), b7 = _mm256_shuffle_ps(a5, a7, 0xEE);
    const __m256 t[8] = {_mm256_permute2f128_ps(b0, b4, 0x20), _mm256_permute2f128_ps(b1, b5, 0x20),
                         _mm256_permute2f128_ps(b2, b6, 0x20), _mm256_permute2f128_ps(b3, b7, 0x20),
                         _mm256_permute2f128_ps(b0, b4, 0x31), _mm256_permute2f128_ps(b1, b5, 0x31),
                         _mm256_permute2f128_ps(b2, b6, 0x31), _mm256_permute2f128_ps(b3, b7, 0x31)};
    __m256d lo = _mm256_loadu_pd(sums + k), hi = _mm256_loadu_pd(sums + k + 4);
    for (int i = 0; i < 8; ++i) {
      lo = _mm256_add_pd(lo, _mm256_cvtps_pd(_mm256_castps256_ps128(t[i])));
      hi = _mm256_add_pd(hi, _mm256_cvtps_pd(_mm256_extractf128_ps(t[i], 1)));
    }
    _mm256_storeu_pd(sums + k, lo);
    _mm256_storeu_pd(sums + k + 4, hi);
  }
  if (k < cells) scalar::add_cells(v, sums + k, cells - k);
}

// sse2::own_states for 32 voxels per step (the SSE2 one takes the rest).
__attribute__((target("avx2"))) void own_states(const float* p, std::size_t n, float lo, float hi,
                                                std::uint8_t* out) {
  const __m256 l = _mm256_set1_ps(lo), h = _mm256_set1_ps(hi);
  const __m256i one = _mm256_set1_epi32(1), order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  std::size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    __m256i s[4];
    for (int j = 0; j < 4; ++j) {  // 1 + (p < lo ? -1 : 0) - (p > hi ? -1 : 0)
      const __m256 a = _mm256_loadu_ps(p + i + 8 * j);
      s[j] = _mm256_sub_epi32(_mm256_add_epi32(one, _mm256_castps_si256(_mm256_cmp_ps(a, l, _CMP_LT_OQ))),
                              _mm256_castps_si256(_mm256_cmp_ps(a, h, _CMP_GT_OQ)));
    }
    // The packs work within 128-bit halves: dwords come out as (0-3 of each s) (4-7 of each s).
    const __m256i bytes = _mm256_packs_epi16(_mm256_packs_epi32(s[0], s[1]), _mm256_packs_epi32(s[2], s[3]));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), _mm256_permutevar8x32_epi32(bytes, order));
  }
  sse2::own_states(p + i, n - i, lo, hi, out + i);
}

// scalar::own_bits 64 voxels per step (8 compares of 8 each; the scalar one takes the rest). NaN
// counts as unknown, as in the scalar one.
__attribute__((target("avx2"))) void own_bits(const float* p, std::size_t n, float lo, float hi, word_t* u,
                                              word_t* o) {
  const __m256 l = _mm256_set1_ps(lo), h = _mm256_set1_ps(hi);
  std::size_t i = 0;
  for (; i + 64 <= n; i += 64) {
    std::uint64_t uw = 0, ow = 0;
    for (int j = 0; j < 8; ++j) {
      const __m256 a = _mm256_loadu_ps(p + i + 8 * j);
      const __m256 in = _mm256_and_ps(_mm256_cmp_ps(a, l, _CMP_NLT_UQ), _mm256_cmp_ps(a, h, _CMP_NGT_UQ));
      uw |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(in))) << (8 * j);
      ow |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a, h, _CMP_GT_OQ))))
            << (8 * j);
    }
    u[i / 64] = uw;
    o[i / 64] = ow;
  }
  if (i < n) scalar::own_bits(p + i, n - i, lo, hi, u + i / 64, o + i / 64);
}

}  // namespace occseg::kernels::avx2
#endif
