// The texture kernels in AVX-512 (kernels/texture.hpp): the first pass's row kernel (with a
// VBMI variant), its counting of steps (VBMI2) and the second pass from parked LBP codes.
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/generic/texture_loops.hpp"
#include "kernels/texture_impl.hpp"

namespace occseg::kernels::avx512 {

namespace {

// (GCC 12 warns inside its own AVX-512 intrinsics, whose pass-through operands are deliberately
// undefined.)
#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// Byte i of the result is byte idx[i] % 64 of `table`: AVX-512 VBMI's vpermb, written as assembly
// so that the AVX-512 F/BW/VL kernel can hold it in its VBMI variant (a function compiled for
// VBMI could not be the other variant too, and the compilers will not inline a VBMI function
// into one that is not). Called only where the processor has VBMI.
__attribute__((target("avx512f,avx512bw,avx512vl"))) inline __m512i permute_bytes_vbmi(__m512i idx, __m512i table) {
  __m512i r;
  asm("vpermb %2, %1, %0" : "=v"(r) : "v"(idx), "v"(table));
  return r;
}

// The voxels x .. x + 15 of the row at p where `m` has their bits (the others are not read or
// written); `top_bits` keeps the largest bit pattern of the centres seen (as unsigned integers:
// [+0, 1] is 0 .. 0x3F800000, so anything above is outside it, NaN or -0.0), `rc` gathers the
// kRecheckStep voxels.
//
// The LBP code and the count of neighbours >= the centre are built in bytes (16 per 128-bit
// vector: cheaper than the 16 x 32-bit lanes of the floats), and each side's sum is one chain of
// masked additions in neighbour order: another order than the AVX2 kernel's tree of pairs, which
// the certificate allows (any order of at most six floats in [0, 1] is within 5u * sum of the
// exact sum, see avx2::contrast_row), and fewer operations than that tree's masked moves and
// additions.
//
// With Vbmi (for processors with AVX-512 VBMI), the count of neighbours above is looked up from
// the LBP code (one byte permute through a table of the 64 codes' bit counts) instead of counted
// by six masked additions beside it.
template <bool Vbmi>
__attribute__((target("avx512f,avx512bw,avx512vl"))) inline void contrast16(const float* p, const std::ptrdiff_t* o,
                                                                           std::size_t x, __mmask16 m, code_t* out,
                                                                           std::uint8_t* lbp, __m512i& top_bits,
                                                                           __mmask16& rc) {
  const __m512 zero = _mm512_setzero_ps(), err = _mm512_set1_ps(1e-6f);
  const __m512 fine = _mm512_set1_ps(static_cast<float>(ContrastQuantizer::kFine));
  const __m512i top = _mm512_set1_epi32(ContrastQuantizer::kFine - 1), recheck = _mm512_set1_epi32(kRecheckStep);
  const __m512i inc = _mm512_set1_epi32(1);
  // 1 / count by the count of neighbours above (recip) and by that of those below (recip_below:
  // 1 / (6 - count), the count above being its index).
  const __m512 recip = _mm512_setr_ps(1.0f, 1.0f, 1.0f / 2, 1.0f / 3, 1.0f / 4, 1.0f / 5, 1.0f / 6, 1.0f, 1.0f, 1.0f,
                                      1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f);
  const __m512 recip_below = _mm512_setr_ps(1.0f / 6, 1.0f / 5, 1.0f / 4, 1.0f / 3, 1.0f / 2, 1.0f, 1.0f, 1.0f, 1.0f,
                                            1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f);
  const __m128i one8 = _mm_set1_epi8(1);
  const __m512 c = _mm512_maskz_loadu_ps(m, p + x);
  top_bits = _mm512_max_epu32(top_bits, _mm512_castps_si512(c));  // masked lanes: +0.0
  __m512 sum1 = _mm512_setzero_ps(), sum0 = _mm512_setzero_ps();
  __m128i up8 = _mm_setzero_si128(), bits = _mm_setzero_si128();
  for (int k = 0; k < 6; ++k) {
    const __m512 v = _mm512_maskz_loadu_ps(m, p + x + o[k]);
    const __mmask16 up = _mm512_cmp_ps_mask(v, c, _CMP_GE_OQ);
    bits = _mm_mask_add_epi8(bits, up, bits, _mm_set1_epi8(static_cast<char>(1 << k)));
    if constexpr (!Vbmi) up8 = _mm_mask_add_epi8(up8, up, up8, one8);
    sum1 = _mm512_mask_add_ps(sum1, up, sum1, v);
    sum0 = _mm512_mask_add_ps(sum0, static_cast<__mmask16>(~up), sum0, v);
  }
  if constexpr (Vbmi) {
    // byte k of the table: the number of bits set in k (k < 64: an LBP code)
    const __m512i bit_counts = _mm512_set_epi8(
        6, 5, 5, 4, 5, 4, 4, 3, 5, 4, 4, 3, 4, 3, 3, 2, 5, 4, 4, 3, 4, 3, 3, 2, 4, 3, 3, 2, 3, 2, 2, 1,
        5, 4, 4, 3, 4, 3, 3, 2, 4, 3, 3, 2, 3, 2, 2, 1, 4, 3, 3, 2, 3, 2, 2, 1, 3, 2, 2, 1, 2, 1, 1, 0);
    up8 = _mm512_castsi512_si128(permute_bytes_vbmi(_mm512_zextsi128_si512(bits), bit_counts));
  }
  const __m512i up_count = _mm512_cvtepu8_epi32(up8);
  const __m512 con = _mm512_sub_ps(_mm512_mul_ps(sum1, _mm512_permutexvar_ps(up_count, recip)),
                                   _mm512_mul_ps(sum0, _mm512_permutexvar_ps(up_count, recip_below)));
  // Neighbours on both sides: the LBP code is neither 0 nor 63.
  const __mmask16 two_sided = static_cast<__mmask16>(_mm_test_epi8_mask(bits, bits) &
                                                     _mm_cmpneq_epi8_mask(bits, _mm_set1_epi8(63)));
  const __m512 lo = _mm512_mul_ps(_mm512_sub_ps(con, err), fine), hi = _mm512_mul_ps(_mm512_add_ps(con, err), fine);
  const __m512i step = _mm512_min_epi32(_mm512_cvttps_epi32(lo), top);
  const __m512i step_hi = _mm512_min_epi32(_mm512_cvttps_epi32(hi), top);
  const __mmask16 sure = static_cast<__mmask16>(_mm512_cmp_ps_mask(lo, zero, _CMP_GT_OQ) &
                                                _mm512_cmpeq_epi32_mask(step, step_hi));
  rc = static_cast<__mmask16>(rc | (m & two_sided & ~sure));
  const __m512i v = _mm512_mask_blend_epi32(sure, recheck, _mm512_add_epi32(step, inc));
  // Values <= 0xFFFF: truncating to 16 bits keeps them.
  _mm256_mask_storeu_epi16(out + x, m, _mm512_cvtepi32_epi16(_mm512_maskz_mov_epi32(two_sided, v)));
  if (lbp) _mm_mask_storeu_epi8(lbp + x, m, bits);
}

// avx2::contrast_row for 16 voxels per step: the same certificate and check, the sums in another
// order (contrast16), so a float contrast may differ in its last bits and a voxel be rechecked by
// one kernel and not the other, but the steps are texture_unit()'s in both, and the LBP codes the
// same; comparisons go to mask registers, which removes the and/andnot selections and the
// register spills of the AVX2 loop. The last n % 16 voxels are one masked step (no scalar tail).
// `maybe_recheck` is set exactly when some voxel is kRecheckStep.
template <bool Vbmi>
__attribute__((target("avx512f,avx512bw,avx512vl"))) bool contrast_row_impl(const float* p, const std::ptrdiff_t* off,
                                                                             std::size_t n, code_t* out,
                                                                             std::uint8_t* lbp, bool& maybe_recheck) {
  const std::ptrdiff_t o[6] = {off[0], off[1], off[2], off[3], off[4], off[5]};  // see avx2::contrast_row
  __m512i top_bits = _mm512_setzero_si512();
  __mmask16 rc = 0;
  std::size_t x = 0;
  for (; x + 16 <= n; x += 16) contrast16<Vbmi>(p, o, x, 0xFFFF, out, lbp, top_bits, rc);
  if (x < n) contrast16<Vbmi>(p, o, x, static_cast<__mmask16>((1u << (n - x)) - 1), out, lbp, top_bits, rc);
  maybe_recheck = rc != 0;
  // One test per row instead of two compares per step; a row with -0.0 (valid) takes the exact check.
  return _mm512_cmpgt_epu32_mask(top_bits, _mm512_set1_epi32(0x3F800000)) == 0 || generic::values_in_range(p, n);
}

}  // namespace

__attribute__((target("avx512f,avx512bw,avx512vl"))) bool contrast_row(const float* p, const std::ptrdiff_t* off,
                                                                        std::size_t n, code_t* steps,
                                                                        std::uint8_t* lbp, bool& maybe_recheck) {
  return contrast_row_impl<false>(p, off, n, steps, lbp, maybe_recheck);
}

__attribute__((target("avx512f,avx512bw,avx512vl"))) bool contrast_row_vbmi(const float* p, const std::ptrdiff_t* off,
                                                                             std::size_t n, code_t* steps,
                                                                             std::uint8_t* lbp, bool& maybe_recheck) {
  return contrast_row_impl<true>(p, off, n, steps, lbp, maybe_recheck);
}

// avx2::count_steps with the non-zero steps of 32 voxels at a time packed by one compress
// instruction (AVX-512 VBMI2) instead of a table of shuffles per 8; `list` needs room for n + 32.
__attribute__((target("avx512f,avx512bw,avx512vl,avx512vbmi2"))) void count_steps(const code_t* v, std::size_t n,
                                                                                   std::uint64_t* h,
                                                                                   std::uint16_t* list) {
  std::size_t len = 0;
  for (std::size_t x = 0; x < n; x += 32) {  // the last n % 32 masked
    const auto in = static_cast<__mmask32>(n - x >= 32 ? ~0u : (1u << (n - x)) - 1);
    const __m512i s = _mm512_maskz_loadu_epi16(in, v + x);
    const __mmask32 m = _mm512_test_epi16_mask(s, s);
    _mm512_storeu_si512(list + len, _mm512_maskz_compress_epi16(m, s));
    len += static_cast<std::size_t>(__builtin_popcount(m));
  }
  generic::count_list(list, len, h);
}

// avx2::codes_from_lbp for 32 voxels per step (AVX-512 BW): the same operations on each lane,
// the last n % 32 voxels in one masked step.
__attribute__((target("avx512f,avx512bw,avx512vl"))) void codes_from_lbp(code_t* row, const std::uint8_t* lbp,
                                                                          std::size_t n, const std::uint16_t* rises,
                                                                          std::size_t nr, std::uint16_t bins) {
  __m512i rise[16];
  for (std::size_t k = 0; k < nr; ++k) rise[k] = _mm512_set1_epi16(static_cast<short>(rises[k]));
  const __m512i one = _mm512_set1_epi16(1), b = _mm512_set1_epi16(static_cast<short>(bins));
  for (std::size_t x = 0; x < n; x += 32) {
    const auto m = static_cast<__mmask32>(n - x >= 32 ? ~0u : (1u << (n - x)) - 1);
    const __m512i v = _mm512_maskz_loadu_epi16(m, row + x);
    __m512i lvl = _mm512_maskz_mov_epi16(_mm512_test_epi16_mask(v, v), one);
    for (std::size_t k = 0; k < nr; ++k) lvl = _mm512_mask_add_epi16(lvl, _mm512_cmpgt_epi16_mask(v, rise[k]), lvl, one);
    const __m512i l = _mm512_cvtepu8_epi16(_mm256_maskz_loadu_epi8(m, lbp + x));
    _mm512_mask_storeu_epi16(row + x, m, _mm512_add_epi16(_mm512_mullo_epi16(l, b), lvl));
  }
}
#pragma GCC diagnostic pop

}  // namespace occseg::kernels::avx512
#endif
