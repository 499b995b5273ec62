#include "stages/texture.hpp"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <immintrin.h>

#include "stages/create.hpp"
#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "kernels/cpu_features.hpp"
#include "stages/codes.hpp"
#include "util/huge_pages.hpp"
#include "kernels/avx2/lane_pack.hpp"
#include "stages/own_states.hpp"
#include "util/thread_scratch.hpp"

namespace occseg {

TextureUnit texture_unit(double centre, const double n[6], unsigned present) {
  // The same arithmetic as the vectorised row kernel below: masked sums in neighbour order
  // (adding 0.0 for the other side is exact), so both give bit-identical contrasts.
  TextureUnit u;
  double sum1 = 0, sum0 = 0;
  int n1 = 0, n0 = 0;
  for (int i = 0; i < 6; ++i) {
    if (!(present & (1u << i))) continue;
    if (n[i] >= centre) {
      u.lbp = static_cast<std::uint8_t>(u.lbp | (1u << i));
      sum1 += n[i];
      ++n1;
    } else {
      sum0 += n[i];
      ++n0;
    }
  }
  u.contrast = (n1 && n0) ? sum1 / n1 - sum0 / n0 : 0.0;
  return u;
}

ContrastQuantizer::ContrastQuantizer(int bins, const std::vector<std::uint64_t>& fine)
    : bins_(bins), lut_(kFine, 1) {
  if (bins < 2 || bins > 64 || fine.size() != static_cast<std::size_t>(kFine))
    throw Error(Status::invalid_argument, "contrast_bins must be in [2, 64]");
  std::uint64_t total = 0;
  for (auto c : fine) total += c;
  const int levels = bins - 1;  // non-zero contrast levels
  if (total == 0 || levels == 1) return;
  // cut[k] = first fine step whose cumulative count reaches k/levels of the total; a step belongs
  // to level 1 + #{k : cut[k] < step}, so ties (equal contrasts) always share one level.
  std::vector<int> cut;
  std::uint64_t cum = 0;
  int k = 1;
  for (int f = 0; f < kFine && k < levels; ++f) {
    cum += fine[f];
    while (k < levels && cum * levels >= total * static_cast<std::uint64_t>(k)) {
      cut.push_back(f);
      ++k;
    }
  }
  for (int f = 0; f < kFine; ++f) {
    int lvl = 1;
    for (int c : cut) lvl += (c < f);
    lut_[f] = static_cast<std::uint8_t>(lvl);
  }
}

namespace {

// Offsets of the six neighbours; an absent neighbour (axis of size 1) has offset 0 and is masked
// out by `present`.
struct Stencil {
  std::ptrdiff_t off[6];
  unsigned present;
};

// Marks a voxel whose fine step the float kernel cannot certify (see contrast_row_impl).
constexpr std::uint16_t kRecheck = 0xFFFF;

// Fine contrast step + 1 of `n` consecutive interior voxels starting at p (0: C <= 0), written
// to out. The reference arithmetic is texture_unit()'s, in double; this kernel runs in float
// (8 lanes), which is exact for the comparisons (floats compare the same in double) and within
// 1e-6 of the double contrast: each mean of at most six floats in [0, 1] has a float error below
// 6 * 2^-24 * mean < 3.6e-7, the difference below 7.8e-7. A voxel gets its step from the float
// value only when the whole interval c +- 1e-6 lies in one step (and above 0); otherwise (about
// 1 voxel in 100 on noisy maps, fewer on real ones) it is marked kRecheck and recomputed in
// double by the caller, so the steps are exactly those of texture_unit().
//
// With Clamp, defined for any float (a NaN or an infinity among the values: the vector kernels'
// tails, whose rows are checked as they are computed, not before): the float steps are clamped
// into [-1, kTop] before the conversion, which changes no valid voxel's step. Without it (the
// rows of the compiler-vectorised kernel, whose map is checked plane by plane ahead of it) the
// loop vectorises; with it GCC 12 leaves it scalar (6 -> 17 ns per voxel).
template <unsigned Present, bool Clamp = false>
inline void contrast_row_impl(const float* p, const std::ptrdiff_t* off, std::size_t n, detail::code_t* out) {
  const std::ptrdiff_t o0 = off[0], o1 = off[1], o2 = off[2], o3 = off[3], o4 = off[4], o5 = off[5];
  constexpr float kErr = 1e-6f, kFine = ContrastQuantizer::kFine;
  constexpr int kTop = ContrastQuantizer::kFine - 1;
  for (std::size_t x = 0; x < n; ++x) {
    const float c = p[x];
    float s1 = 0, s0 = 0, n1 = 0, n0 = 0;
#define OCCSEG_NB(K, O)                         \
  if (Present & (1u << K)) {                    \
    const float v = p[std::ptrdiff_t(x) + O];   \
    const bool up = v >= c;                     \
    s1 += up ? v : 0.0f;                        \
    s0 += up ? 0.0f : v;                        \
    n1 += up ? 1.0f : 0.0f;                     \
    n0 += up ? 0.0f : 1.0f;                     \
  }
    OCCSEG_NB(0, o0) OCCSEG_NB(1, o1) OCCSEG_NB(2, o2) OCCSEG_NB(3, o3) OCCSEG_NB(4, o4) OCCSEG_NB(5, o5)
#undef OCCSEG_NB
    const float con = s1 / (n1 > 0 ? n1 : 1.0f) - s0 / (n0 > 0 ? n0 : 1.0f);
    const bool two_sided = (n1 > 0) & (n0 > 0);
    float lo = (con - kErr) * kFine, hi = (con + kErr) * kFine;  // |con| <= 1 for a valid map
    if constexpr (Clamp) {  // std::max(-1, v) is -1 for a NaN v
      lo = std::min(std::max(-1.0f, lo), float(kTop));
      hi = std::min(std::max(-1.0f, hi), float(kTop));
    }
    int step = static_cast<int>(lo), step_hi = static_cast<int>(hi);
    step = step < kTop ? step : kTop;
    step_hi = step_hi < kTop ? step_hi : kTop;
    const bool sure = (lo > 0.0f) & (step == step_hi);
    const int v = sure ? step + 1 : int(kRecheck);
    out[x] = static_cast<std::uint16_t>(two_sided ? v : 0);
  }
}

// The exact (double) fine step + 1 of one voxel, for kRecheck voxels.
std::uint16_t exact_step(const float* p, const std::ptrdiff_t* off, unsigned present) {
  double nb[6];
  for (int k = 0; k < 6; ++k) nb[k] = p[off[k]];
  const TextureUnit u = texture_unit(p[0], nb, present);
  // A valid map's contrasts lie in [0, 1]; anything else (NaN, infinities: an invalid map, which
  // pass 1 reports once it ends) must not reach fine_step's conversion.
  return u.contrast > 0 && u.contrast <= 1 ? static_cast<std::uint16_t>(ContrastQuantizer::fine_step(u.contrast) + 1)
                                           : 0;
}

// LBP codes of `n` consecutive interior voxels.
template <unsigned Present>
inline void lbp_row_impl(const float* p, const std::ptrdiff_t* off, std::size_t n, std::uint8_t* out) {
  const std::ptrdiff_t o0 = off[0], o1 = off[1], o2 = off[2], o3 = off[3], o4 = off[4], o5 = off[5];
  for (std::size_t x = 0; x < n; ++x) {
    const float c = p[x];
    std::uint8_t l = 0;
#define OCCSEG_BIT(K, O) \
  if (Present & (1u << K)) l |= p[std::ptrdiff_t(x) + O] >= c ? std::uint8_t(1u << K) : std::uint8_t(0);
    OCCSEG_BIT(0, o0) OCCSEG_BIT(1, o1) OCCSEG_BIT(2, o2) OCCSEG_BIT(3, o3) OCCSEG_BIT(4, o4) OCCSEG_BIT(5, o5)
#undef OCCSEG_BIT
    out[x] = l;
  }
}

// The hot 3D kernels, compiled for AVX2 and for baseline x86-64 with run-time dispatch.
__attribute__((target_clones("avx2", "default")))
void contrast_row_3d(const float* p, const std::ptrdiff_t* off, std::size_t n, detail::code_t* out) {
  contrast_row_impl<63>(p, off, n, out);
}
__attribute__((target_clones("avx2", "default")))
void lbp_row_3d(const float* p, const std::ptrdiff_t* off, std::size_t n, std::uint8_t* out) {
  lbp_row_impl<63>(p, off, n, out);
}

#if defined(__x86_64__) && defined(__GNUC__)
#define OCCSEG_TEXTURE_AVX2 1
// contrast_row_impl<63>'s steps, 8 voxels per step in hand-written AVX2. The float contrast is
// computed differently (the six masked neighbours summed as a tree of pairs, each mean as
// sum * fl(1 / count) with the reciprocal looked up by count): shorter dependency chains and no
// divisions (with the step counting below, texture stage 34 -> 28 ms on two threads). The
// certificate still holds: a sum of at most six floats in [0, 1] in any order is within 5u * sum
// of the exact sum (u = 2^-24), the rounded reciprocal and the product add 2u, so each mean is
// within 7u <= 4.2e-7 of its exact value, the difference within 8.4e-7 + u * |c| < 9e-7 of the
// double contrast, and c +- 1e-6 (each bound rounded by at most 6e-8) still encloses it. So the
// sure steps are texture_unit()'s, as are the kRecheck voxels', whichever kernel ran. No FMA in
// the interval itself: it would change the rounding the bound accounts for.
//
// With `lbp` (else nullptr), the voxels' LBP codes go there too, from the same comparisons.
//
// The row's values are checked here too: returns false when one of p[0..n) is not in [0, 1]
// (NaN included). A map is then rejected after the pass, and its codes are never used; the
// arithmetic above is defined for any float (the conversions of NaN or huge values give INT_MIN,
// below every step). Checking the centres as they are loaded replaced a separate check of each
// plane before its texture (4.6 of 43 ms of this pass on one thread).
//
// Rows of 8 voxels or more end with a step that overlaps the one before (its voxels' results
// depend on the map only) instead of a scalar tail, which cost a row of 318 as much as 40 of its
// voxels. `any_recheck` is set when some voxel is kRecheck (no scan of the row for them).
__attribute__((target("avx2"))) bool contrast_row_avx2(const float* p, const std::ptrdiff_t* off, std::size_t n,
                                                       detail::code_t* out, std::uint8_t* lbp, bool& any_recheck) {
  if (n < 8) {
    contrast_row_impl<63, true>(p, off, n, out);
    if (lbp) lbp_row_impl<63>(p, off, n, lbp);
    any_recheck = std::find(out, out + n, kRecheck) != out + n;
    return probabilities_in_range(p, n);
  }
  __m256i rc = _mm256_setzero_si256();
  const __m256 zero = _mm256_setzero_ps(), err = _mm256_set1_ps(1e-6f), one = _mm256_set1_ps(1.0f);
  __m256 bad = zero;
  const __m256 fine = _mm256_set1_ps(static_cast<float>(ContrastQuantizer::kFine));
  const __m256i top = _mm256_set1_epi32(ContrastQuantizer::kFine - 1), recheck = _mm256_set1_epi32(kRecheck);
  const __m256i inc = _mm256_set1_epi32(1), six = _mm256_set1_epi32(6);
  const __m256 recip = _mm256_setr_ps(1.0f, 1.0f, 1.0f / 2, 1.0f / 3, 1.0f / 4, 1.0f / 5, 1.0f / 6, 1.0f);
  // Offsets in locals: read through `off` they were reloaded every step (the stores to `out`
  // might alias them).
  const std::ptrdiff_t o[6] = {off[0], off[1], off[2], off[3], off[4], off[5]};
  for (std::size_t x = 0;; x = std::min(x + 8, n - 8)) {
    const __m256 c = _mm256_loadu_ps(p + x);
    bad = _mm256_or_ps(bad, _mm256_or_ps(_mm256_cmp_ps(c, zero, _CMP_NGE_UQ), _mm256_cmp_ps(c, one, _CMP_NLE_UQ)));
    // Neighbours in pairs (x, y, z), the pair sums added as a tree: three additions deep instead
    // of six, so the chains of successive steps overlap (the error bound holds for any order).
    __m256 s1[3], s0[3];
    __m256i up_count = _mm256_setzero_si256();  // neighbours >= centre; the other 6 - count are below
    __m256i bits = _mm256_setzero_si256();      // the LBP codes
    for (int k = 0; k < 3; ++k) {
      const __m256 v = _mm256_loadu_ps(p + x + o[2 * k]), w = _mm256_loadu_ps(p + x + o[2 * k + 1]);
      const __m256 vu = _mm256_cmp_ps(v, c, _CMP_GE_OQ), wu = _mm256_cmp_ps(w, c, _CMP_GE_OQ);
      if (lbp)
        bits = _mm256_or_si256(bits, _mm256_or_si256(_mm256_and_si256(_mm256_castps_si256(vu), _mm256_set1_epi32(1 << (2 * k))),
                                                     _mm256_and_si256(_mm256_castps_si256(wu), _mm256_set1_epi32(2 << (2 * k)))));
      s1[k] = _mm256_add_ps(_mm256_and_ps(vu, v), _mm256_and_ps(wu, w));
      s0[k] = _mm256_add_ps(_mm256_andnot_ps(vu, v), _mm256_andnot_ps(wu, w));
      // a true compare is -1
      up_count = _mm256_sub_epi32(up_count, _mm256_add_epi32(_mm256_castps_si256(vu), _mm256_castps_si256(wu)));
    }
    const __m256 sum1 = _mm256_add_ps(_mm256_add_ps(s1[0], s1[1]), s1[2]);
    const __m256 sum0 = _mm256_add_ps(_mm256_add_ps(s0[0], s0[1]), s0[2]);
    // Means as sum * (1 / count) (1 / 0 is taken as 1: that sum is 0, and the voxel is one-sided).
    const __m256 con = _mm256_sub_ps(_mm256_mul_ps(sum1, _mm256_permutevar8x32_ps(recip, up_count)),
                                     _mm256_mul_ps(sum0, _mm256_permutevar8x32_ps(recip, _mm256_sub_epi32(six, up_count))));
    const __m256i two_sided = _mm256_and_si256(_mm256_cmpgt_epi32(up_count, _mm256_setzero_si256()),
                                               _mm256_cmpgt_epi32(six, up_count));
    const __m256 lo = _mm256_mul_ps(_mm256_sub_ps(con, err), fine), hi = _mm256_mul_ps(_mm256_add_ps(con, err), fine);
    const __m256i step = _mm256_min_epi32(_mm256_cvttps_epi32(lo), top);
    const __m256i step_hi = _mm256_min_epi32(_mm256_cvttps_epi32(hi), top);
    const __m256i sure = _mm256_and_si256(_mm256_castps_si256(_mm256_cmp_ps(lo, zero, _CMP_GT_OQ)),
                                          _mm256_cmpeq_epi32(step, step_hi));
    const __m256i v = _mm256_blendv_epi8(recheck, _mm256_add_epi32(step, inc), sure);
    const __m256i res = _mm256_and_si256(v, two_sided);
    rc = _mm256_or_si256(rc, _mm256_andnot_si256(sure, two_sided));
    // 32 -> 16 bits (values <= 0xFFFF): packus works per 128-bit half, the permute restores order.
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi32(res, res), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm256_castsi256_si128(packed));
    if (lbp) {  // 32 -> 16 -> 8 bits, in order as above
      const __m256i b16 = _mm256_permute4x64_epi64(_mm256_packus_epi32(bits, bits), 0x08);
      const __m128i b8 = _mm_packus_epi16(_mm256_castsi256_si128(b16), _mm256_castsi256_si128(b16));
      _mm_storel_epi64(reinterpret_cast<__m128i*>(lbp + x), b8);
    }
    if (x + 8 == n) break;
  }
  any_recheck = !_mm256_testz_si256(rc, rc);
  return _mm256_testz_ps(bad, bad);
}

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
// kRecheck voxels.
//
// The LBP code and the count of neighbours >= the centre are built in bytes (16 per 128-bit
// vector: cheaper than the 16 x 32-bit lanes of the floats), and each side's sum is one chain of
// masked additions in neighbour order: another order than the AVX2 kernel's tree of pairs, which
// the certificate allows (any order of at most six floats in [0, 1] is within 5u * sum of the
// exact sum, see contrast_row_avx2), and 25 % fewer cycles per voxel than that tree's masked
// moves and additions (1.09 -> 0.82 ns per voxel on one thread, rows in L2).
//
// With Vbmi (for processors with AVX-512 VBMI: Ice Lake and later), the count of neighbours above
// is looked up from the LBP code (one byte permute through a table of the 64 codes' bit counts)
// instead of counted by six masked additions beside it: six of the step's ~50 vector operations
// fewer (texture stage 14.0-14.6 -> 13.2-13.4 ms on the scene, 2 threads).
template <bool Vbmi>
__attribute__((target("avx512f,avx512bw,avx512vl"))) inline void contrast16(const float* p, const std::ptrdiff_t* o,
                                                                           std::size_t x, __mmask16 m,
                                                                           detail::code_t* out, std::uint8_t* lbp,
                                                                           __m512i& top_bits, __mmask16& rc) {
  const __m512 zero = _mm512_setzero_ps(), err = _mm512_set1_ps(1e-6f);
  const __m512 fine = _mm512_set1_ps(static_cast<float>(ContrastQuantizer::kFine));
  const __m512i top = _mm512_set1_epi32(ContrastQuantizer::kFine - 1), recheck = _mm512_set1_epi32(kRecheck);
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

// contrast_row_avx2 for 16 voxels per step in AVX-512 (F, BW, VL): the same certificate and
// check, the sums in another order (contrast16), so a float contrast may differ in its last bits
// and a voxel be rechecked by one kernel and not the other, but the steps are texture_unit()'s
// in both, and the LBP codes the same; comparisons go to mask registers, which removes the
// and/andnot selections and the register spills of the AVX2 loop (about 105 instructions per 8
// voxels there). The last n % 16 voxels are one masked step (a scalar tail cost a row of 318 as
// much as 40 of its voxels). `any_recheck` is set when some voxel is kRecheck.
template <bool Vbmi>
__attribute__((target("avx512f,avx512bw,avx512vl"))) bool contrast_row_avx512(const float* p,
                                                                               const std::ptrdiff_t* off, std::size_t n,
                                                                               detail::code_t* out, std::uint8_t* lbp,
                                                                               bool& any_recheck) {
  const std::ptrdiff_t o[6] = {off[0], off[1], off[2], off[3], off[4], off[5]};  // see contrast_row_avx2
  __m512i top_bits = _mm512_setzero_si512();
  __mmask16 rc = 0;
  std::size_t x = 0;
  for (; x + 16 <= n; x += 16) contrast16<Vbmi>(p, o, x, 0xFFFF, out, lbp, top_bits, rc);
  if (x < n) contrast16<Vbmi>(p, o, x, static_cast<__mmask16>((1u << (n - x)) - 1), out, lbp, top_bits, rc);
  any_recheck = rc != 0;
  // One test per row instead of two compares per step; a row with -0.0 (valid) takes the exact check.
  return _mm512_cmpgt_epu32_mask(top_bits, _mm512_set1_epi32(0x3F800000)) == 0 || probabilities_in_range(p, n);
}
#pragma GCC diagnostic pop

// Pass 2 for 8 voxels per step, in place: row[x] = lbp * bins + level, from the parked step
// v = row[x] (level = (v != 0) + #{k : v > rises[k]}) and the six comparisons of the LBP code
// (the same `>=` as lbp_row_impl). One pass instead of three over the row (LBP codes, levels,
// combination). Returns the voxels done (a multiple of 8); the caller finishes the row.
__attribute__((target("avx2"))) std::size_t codes_row_avx2(const float* p, const std::ptrdiff_t* off, std::size_t n,
                                                           const std::uint16_t* rises, std::size_t nr,
                                                           std::uint16_t bins, detail::code_t* row) {
  __m256i rise[16];
  for (std::size_t k = 0; k < nr; ++k) rise[k] = _mm256_set1_epi32(rises[k]);
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi32(1);
  // Bit k of the LBP code weighs bins << k, and the weights are added: the code comes out
  // multiplied by bins (no multiply).
  __m256i weight[6];
  for (int k = 0; k < 6; ++k) weight[k] = _mm256_set1_epi32(bins << k);
  const std::ptrdiff_t o[6] = {off[0], off[1], off[2], off[3], off[4], off[5]};  // see contrast_row_avx2
  std::size_t x = 0;
  for (; x + 8 <= n; x += 8) {
    const __m256 c = _mm256_loadu_ps(p + x);
    __m256i lbp_bins = zero;  // lbp * bins
    for (int k = 0; k < 6; ++k) {
      const __m256 up = _mm256_cmp_ps(_mm256_loadu_ps(p + x + o[k]), c, _CMP_GE_OQ);
      lbp_bins = _mm256_add_epi32(lbp_bins, _mm256_and_si256(_mm256_castps_si256(up), weight[k]));  // add: bins may not be a power of 2
    }
    const __m256i v = _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x)));
    __m256i lvl = _mm256_andnot_si256(_mm256_cmpeq_epi32(v, zero), one);
    for (std::size_t k = 0; k < nr; ++k) lvl = _mm256_sub_epi32(lvl, _mm256_cmpgt_epi32(v, rise[k]));  // -(-1)
    const __m256i code = _mm256_add_epi32(lbp_bins, lvl);  // < 64 * 64: fits 16 bits
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi32(code, code), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(row + x), _mm256_castsi256_si128(packed));
  }
  return x;
}

// Pass 2 from parked LBP codes, 16 voxels per step, in place: row[x] = lbp[x] * bins + level,
// the level from the parked step v = row[x] as in codes_row_avx2 (steps <= 4096 compare as
// signed 16-bit values). Returns n.
__attribute__((target("avx2"))) std::size_t codes_from_lbp_avx2(detail::code_t* row, const std::uint8_t* lbp,
                                                                std::size_t n, const std::uint16_t* rises,
                                                                std::size_t nr, std::uint16_t bins) {
  __m256i rise[16];
  for (std::size_t k = 0; k < nr; ++k) rise[k] = _mm256_set1_epi16(static_cast<short>(rises[k]));
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi16(1), b = _mm256_set1_epi16(static_cast<short>(bins));
  // The last n % 16 voxels go through copies padded to 16 (the pass is in place: a step
  // overlapping the one before would read codes as steps).
  alignas(32) std::uint16_t last_v[16] = {};
  alignas(16) std::uint8_t last_l[16] = {};
  for (std::size_t x = 0; x < n; x += 16) {
    const std::size_t m = std::min<std::size_t>(16, n - x);
    std::uint16_t* const at = m == 16 ? row + x : last_v;
    const std::uint8_t* const lat = m == 16 ? lbp + x : last_l;
    if (m < 16) {
      std::memcpy(last_v, row + x, m * sizeof(std::uint16_t));
      std::memcpy(last_l, lbp + x, m);
    }
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at));
    __m256i lvl = _mm256_andnot_si256(_mm256_cmpeq_epi16(v, zero), one);
    for (std::size_t k = 0; k < nr; ++k) lvl = _mm256_sub_epi16(lvl, _mm256_cmpgt_epi16(v, rise[k]));  // -(-1)
    const __m256i l = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(lat)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(at), _mm256_add_epi16(_mm256_mullo_epi16(l, b), lvl));
    if (m < 16) std::memcpy(row + x, last_v, m * sizeof(std::uint16_t));
  }
  return n;
}

#endif

std::atomic<int> g_texture_kernel{static_cast<int>(detail::TextureKernel::fastest)};

[[maybe_unused]] bool use_avx2_kernel() {
  return cpu_has_avx2() && g_texture_kernel.load(std::memory_order_relaxed) >= static_cast<int>(detail::TextureKernel::avx2);
}
[[maybe_unused]] bool use_avx512_kernel() {
  return cpu_has_avx512() && g_texture_kernel.load(std::memory_order_relaxed) >= static_cast<int>(detail::TextureKernel::avx512);
}
[[maybe_unused]] bool use_vbmi_kernel() {
  return cpu_has_avx512vbmi() &&
         g_texture_kernel.load(std::memory_order_relaxed) >= static_cast<int>(detail::TextureKernel::avx512vbmi);
}

// True when some v[x] is kRecheck (branch-free, so it vectorises: rechecks are rare).
__attribute__((target_clones("avx2", "default")))
bool any_recheck(const detail::code_t* v, std::size_t n) {
  unsigned any = 0;
  for (std::size_t x = 0; x < n; ++x) any |= v[x] == kRecheck;
  return any != 0;
}

// Adds the fine steps v[0..n) to four interleaved histograms (h + k * kStepStride; entry 0 counts
// flat voxels and is not used). Four voxels whose steps are all 0 (flat regions: most of a map)
// are skipped with one test; otherwise each goes to its own histogram, so runs of equal steps do
// not chain their increments through one counter.
constexpr std::size_t kStepStride = ContrastQuantizer::kFine + 1;
void count_steps(const detail::code_t* v, std::size_t n, std::uint64_t* h) {
  std::size_t x = 0;
  for (; x + 4 <= n; x += 4) {
    std::uint64_t four;
    std::memcpy(&four, v + x, 8);
    if (four == 0) continue;
    ++h[v[x]];
    ++h[kStepStride + v[x + 1]];
    ++h[2 * kStepStride + v[x + 2]];
    ++h[3 * kStepStride + v[x + 3]];
  }
  for (; x < n; ++x) ++h[v[x]];
}

// Adds the steps list[0..len) to four interleaved histograms, as count_steps() does.
inline void count_list(const std::uint16_t* list, std::size_t len, std::uint64_t* h) {
  std::size_t i = 0;
  for (; i + 4 <= len; i += 4) {
    ++h[list[i]];
    ++h[kStepStride + list[i + 1]];
    ++h[2 * kStepStride + list[i + 2]];
    ++h[3 * kStepStride + list[i + 3]];
  }
  for (; i < len; ++i) ++h[list[i]];
}

#ifdef OCCSEG_TEXTURE_AVX2
// count_steps() without a branch per group: the non-zero steps of 8 voxels at a time are packed
// to the front of a vector (a table of shuffles indexed by the non-zero mask) and appended to
// `list` (room for n + 8), and only they are counted. On the scene 20 % of the voxels are
// textured, scattered among flat ones, so count_steps()'s "are these four all flat?" is often
// mispredicted (first pass 45.8 -> 44.4 ms on one thread).
__attribute__((target("avx2"))) void count_steps_avx2(const detail::code_t* v, std::size_t n, std::uint64_t* h,
                                                      std::uint16_t* list) {
  std::size_t x = 0, len = 0;
  const __m128i zero = _mm_setzero_si128();
  for (; x + 8 <= n; x += 8) {
    const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(v + x));
    const __m128i flat = _mm_cmpeq_epi16(s, zero);
    const unsigned m = ~static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(flat, flat))) & 0xFFu;
    const __m128i ctl = _mm_load_si128(reinterpret_cast<const __m128i*>(detail::kLanePack.shuffle[m]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(list + len), _mm_shuffle_epi8(s, ctl));
    len += static_cast<std::size_t>(__builtin_popcount(m));
  }
  for (; x < n; ++x) list[len] = v[x], len += v[x] != 0;
  count_list(list, len, h);
}
#endif

// count_steps_avx2() with the non-zero steps of 32 voxels at a time packed by one compress
// instruction (AVX-512 VBMI2) instead of a table of shuffles per 8; `list` needs room for n + 32.
#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // see contrast_row_avx512
#endif
__attribute__((target("avx512f,avx512bw,avx512vl,avx512vbmi2"))) void count_steps_avx512(const detail::code_t* v, std::size_t n,
                                                                               std::uint64_t* h, std::uint16_t* list) {
  std::size_t len = 0;
  for (std::size_t x = 0; x < n; x += 32) {  // the last n % 32 masked
    const auto in = static_cast<__mmask32>(n - x >= 32 ? ~0u : (1u << (n - x)) - 1);
    const __m512i s = _mm512_maskz_loadu_epi16(in, v + x);
    const __mmask32 m = _mm512_test_epi16_mask(s, s);
    _mm512_storeu_si512(list + len, _mm512_maskz_compress_epi16(m, s));
    len += static_cast<std::size_t>(__builtin_popcount(m));
  }
  count_list(list, len, h);
}

// codes_from_lbp_avx2() for 32 voxels per step (AVX-512 BW): the same operations on each lane,
// the last n % 32 voxels in one masked step. Returns n.
__attribute__((target("avx512f,avx512bw,avx512vl"))) std::size_t codes_from_lbp_avx512(detail::code_t* row, const std::uint8_t* lbp,
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
  return n;
}
#pragma GCC diagnostic pop

// lvl[x] = (v[x] != 0) + #{k : v[x] > rises[k]}.
__attribute__((target_clones("avx2", "default")))
void levels_row(const detail::code_t* __restrict v, std::size_t n, const std::uint16_t* rises, std::size_t nr,
                std::uint16_t* __restrict lvl) {
  for (std::size_t x = 0; x < n; ++x) lvl[x] = v[x] != 0;
  for (std::size_t k = 0; k < nr; ++k) {
    const std::uint16_t t = rises[k];
    for (std::size_t x = 0; x < n; ++x) lvl[x] = static_cast<std::uint16_t>(lvl[x] + (v[x] > t));
  }
}

// code[x] = lbp[x] * bins + lvl[x].
__attribute__((target_clones("avx2", "default")))
void combine_row(const std::uint8_t* __restrict lbp, const std::uint16_t* __restrict lvl, std::size_t n,
                 std::uint16_t bins, detail::code_t* __restrict code) {
  for (std::size_t x = 0; x < n; ++x) code[x] = static_cast<std::uint16_t>(lbp[x] * bins + lvl[x]);
}

// The compiler-vectorised kernels (the hand-written ones are picked by the caller). Other
// neighbourhoods (maps with an axis of size 1) are small: no dispatch.
template <unsigned P>
void contrast_any(const float* p, const std::ptrdiff_t* off, std::size_t n, detail::code_t* out, unsigned present) {
  if constexpr (P == 64) {
    (void)p, (void)off, (void)n, (void)out, (void)present;
  } else if (present == P) {
    if (P == 63) contrast_row_3d(p, off, n, out);
    else contrast_row_impl<P>(p, off, n, out);
  } else {
    contrast_any<P + 1>(p, off, n, out, present);
  }
}
template <unsigned P>
void lbp_any(const float* p, const std::ptrdiff_t* off, std::size_t n, std::uint8_t* out, unsigned present) {
  if constexpr (P == 64) {
    (void)p, (void)off, (void)n, (void)out, (void)present;
  } else if (present == P) {
    if (P == 63) lbp_row_3d(p, off, n, out);
    else lbp_row_impl<P>(p, off, n, out);
  } else {
    lbp_any<P + 1>(p, off, n, out, present);
  }
}

// Asks for [p, p + bytes) in L2: the rows two planes ahead, while this plane is computed.
void prefetch_row(const void* p, std::size_t bytes) {
  for (std::size_t b = 0; b < bytes; b += 64) __builtin_prefetch(static_cast<const char*>(p) + b, 0, 2);
}

// Interior voxels of row (y, z): [x0, x1) along x. Returns false for rows on an outer face.
bool interior_row(const Dims& d, std::size_t y, std::size_t z, std::size_t& x0, std::size_t& x1) {
  const bool fx = d.nx == 1, fy = d.ny == 1, fz = d.nz == 1;
  if (!fz && (z == 0 || z == d.nz - 1)) return false;
  if (!fy && (y == 0 || y == d.ny - 1)) return false;
  x0 = fx ? 0 : 1;
  x1 = fx ? 1 : d.nx - 1;
  return x0 < x1;
}

Stencil stencil(const Dims& d) {
  const bool hx = d.nx > 1, hy = d.ny > 1, hz = d.nz > 1;
  const auto sy = static_cast<std::ptrdiff_t>(d.nx), sz = static_cast<std::ptrdiff_t>(d.nx * d.ny);
  Stencil s{{hx ? -1 : 0, hx ? 1 : 0, hy ? -sy : 0, hy ? sy : 0, hz ? -sz : 0, hz ? sz : 0},
            (hx ? 3u : 0u) | (hy ? 12u : 0u) | (hz ? 48u : 0u)};
  return s;
}

}  // namespace

namespace detail {
void set_texture_kernel(TextureKernel k) { g_texture_kernel.store(static_cast<int>(k), std::memory_order_relaxed); }
TextureKernel texture_kernel() { return static_cast<TextureKernel>(g_texture_kernel.load(std::memory_order_relaxed)); }
}  // namespace detail

namespace {
void check_contrast_bins(int contrast_bins) {
  if (contrast_bins < 2 || contrast_bins > 64)
    throw Error(Status::invalid_argument, "contrast_bins = " + std::to_string(contrast_bins) +
                                              " is outside [2, 64]");
}
}  // namespace

TextureMap compute_texture(const Grid& grid, int contrast_bins, int threads) {
  check_contrast_bins(contrast_bins);  // before the code array is allocated
  TextureMap tm;
  tm.bins = contrast_bins;
  resize_huge(tm.codes, grid.dims.count());
  detail::compute_texture_into(grid, contrast_bins, threads, reinterpret_cast<detail::code_t*>(tm.codes.data()));
  return tm;
}

void detail::compute_texture_into(const Grid& grid, int contrast_bins, int threads, code_t* codes,
                                  std::uint8_t* lbp_scratch, CellRows* rows) {
  check_contrast_bins(contrast_bins);
  const Dims& d = grid.dims;
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz;
  const Stencil sten = stencil(d);
  const float* p = grid.p.data();
  // Pass 1: fine contrast step + 1 of every interior voxel, parked in the code array, and the
  // distribution of non-zero contrasts (per-thread histograms summed in thread order: integer
  // counts, so the total is exact whoever counted what). Threads take groups of planes from a
  // shared counter: fixed halves left one thread waiting 0.6-0.8 ms for the other on the scene.
  // A group is 1 to 4 cells deep (kMeanCell planes each, so that a cell's planes stay on one
  // thread: CellRows), at least two groups per thread where the map is deep enough (groups of 8
  // planes, interleaving the threads more, were slower than 32 on the scene: 16.0 against 15.2 ms).
  const std::size_t cells_z = (nz + kMeanCell - 1) / kMeanCell;
  const int wanted = resolve_threads(threads);
  const std::size_t G = kMeanCell * std::clamp<std::size_t>(cells_z / (2 * static_cast<std::size_t>(wanted)), 1, 4);
  const std::size_t groups = (nz + G - 1) / G;
  const int t = std::max(1, std::min<int>(wanted, static_cast<int>(groups)));
  std::vector<detail::ThreadScratch<std::uint64_t>> part(t, detail::ThreadScratch<std::uint64_t>(4 * kStepStride, 0));
  // The input check rides along, so the map is read once for both, and the codes of a bad map
  // are never used: the pass stops and the first bad voxel is named. With the hand-written
  // kernels each row checks its own values (the interior ones in the kernel, as it loads them):
  // a bad value may reach the arithmetic of the rows around it before it is seen, which is
  // defined for any float there. The compiler's kernel is not (float to int conversions): there
  // plane z + 1 is checked just before plane z's texture reads it (and a chunk's first planes
  // before it starts), which cost 4.6 of 41 ms on one thread (docs/performance.md, "Sixth round").
  std::atomic<bool> bad_values{false};
#ifdef OCCSEG_TEXTURE_AVX2
  const bool by_rows = sten.present == 63 && use_avx2_kernel();
#else
  const bool by_rows = false;
#endif
  const std::size_t plane = nx * ny;
  auto plane_ok = [&](std::size_t z) { return by_rows || probabilities_in_range(p + plane * z, plane); };
  std::atomic<std::size_t> next_group{0};
  // Planes [z0, z1) into the histograms h; false when a value outside [0, 1] was seen. A function
  // of its own: inlined into the loop over groups below, GCC 12 compiled it 20 % slower.
  const auto planes = [&](std::size_t z0, std::size_t z1, std::uint64_t* h,
                          std::uint16_t* list_data) __attribute__((noinline)) {
    bool ok = (z0 == 0 || plane_ok(z0 - 1)) && plane_ok(z0);
    for (std::size_t z = z0; ok && z < z1; ++z) {
      if (z + 1 < nz && !(ok = plane_ok(z + 1))) break;
      for (std::size_t y = 0; ok && y < ny; ++y) {
        // Plane z + 2 is fetched from memory into L2 while plane z is computed.
        if (z + 2 < nz) prefetch_row(p + nx * (y + ny * (z + 2)), nx * sizeof(float));
        detail::code_t* row = codes + nx * (y + ny * z);
        const float* const prow = p + nx * (y + ny * z);
        std::size_t x0 = 0, x1 = 0;
        if (!interior_row(d, y, z, x0, x1)) {
          std::fill(row, row + nx, kNoTexture);
          ok = !by_rows || probabilities_in_range(prow, nx);
          if (rows) rows->add_row(y, z);
          continue;
        }
        std::fill(row, row + x0, kNoTexture);
        std::fill(row + x1, row + nx, kNoTexture);
        ok = !by_rows || (probabilities_in_range(prow, x0) && probabilities_in_range(prow + x1, nx - x1));
        const float* prow0 = prow + x0;
        // With scratch, the LBP codes now, from the contrast kernel's own comparisons: pass 2
        // then reads 3 bytes per voxel instead of the map's rows again.
        std::uint8_t* lrow = lbp_scratch ? lbp_scratch + nx * (y + ny * z) + x0 : nullptr;
        bool rechecks = true;  // unless the kernel says there are none
#ifdef OCCSEG_TEXTURE_AVX2
        if (sten.present == 63 && use_avx512_kernel()) {
          ok = (use_vbmi_kernel() ? contrast_row_avx512<true>(prow0, sten.off, x1 - x0, row + x0, lrow, rechecks)
                                  : contrast_row_avx512<false>(prow0, sten.off, x1 - x0, row + x0, lrow, rechecks)) &&
               ok;
        } else if (sten.present == 63 && use_avx2_kernel()) {
          ok = contrast_row_avx2(prow0, sten.off, x1 - x0, row + x0, lrow, rechecks) && ok;
        } else
#endif
        {
          contrast_any<0>(prow0, sten.off, x1 - x0, row + x0, sten.present);
          if (lrow) lbp_any<0>(prow0, sten.off, x1 - x0, lrow, sten.present);
        }
        if (rechecks && any_recheck(row + x0, x1 - x0)) {
          for (std::size_t x = x0; x < x1; ++x)
            if (row[x] == kRecheck) row[x] = exact_step(prow + x, sten.off, sten.present);
        }
#ifdef OCCSEG_TEXTURE_AVX2
        if (use_avx512_kernel() && cpu_has_avx512vbmi2()) count_steps_avx512(row + x0, x1 - x0, h, list_data);
        else if (use_avx2_kernel()) count_steps_avx2(row + x0, x1 - x0, h, list_data);
        else
#endif
        count_steps(row + x0, x1 - x0, h);
        if (rows) rows->add_row(y, z);
      }
    }
    return ok;
  };
  parallel_for(static_cast<std::size_t>(t), t, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      std::uint64_t* h = part[k].data();
      detail::ThreadScratch<std::uint16_t> list(nx + 32);  // count_steps_avx*'s room
      for (std::size_t gi; (gi = next_group.fetch_add(1, std::memory_order_relaxed)) < groups;) {
        if (bad_values.load(std::memory_order_relaxed)) break;  // the map is rejected anyway
        const std::size_t z0 = gi * G;
        if (!planes(z0, std::min(nz, z0 + G), h, list.data())) bad_values.store(true, std::memory_order_relaxed);
      }
    }
  });
  if (bad_values.load()) check_probabilities(grid);  // throws, naming the first bad voxel
  std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
  for (auto& h : part)
    for (std::size_t k = 0; k < 4; ++k)
      for (int f = 0; f < ContrastQuantizer::kFine; ++f) fine[f] += h[k * kStepStride + f + 1];
  const ContrastQuantizer q(contrast_bins, fine);
  // Pass 2: codes = lbp * bins + level, the level looked up from the parked fine step v
  // (v = step + 1, 0 for C = 0). Level = (v != 0) + #{t in rises : v > t}, where `rises` lists
  // each v at which the level goes up (repeated when tied cuts make it jump), so a few vector
  // compares replace the table for the usual handful of levels.
  std::vector<std::uint16_t> level(ContrastQuantizer::kFine + 1, 0);
  for (int f = 0; f < ContrastQuantizer::kFine; ++f) level[f + 1] = static_cast<std::uint16_t>(q.level_of_step(f));
  std::vector<std::uint16_t> rises;
  for (int v = 2; v <= ContrastQuantizer::kFine; ++v)
    for (int k = level[v - 1]; k < level[v]; ++k) rises.push_back(static_cast<std::uint16_t>(v - 1));
  const bool by_compares = rises.size() <= 16;
#ifdef OCCSEG_TEXTURE_AVX2
  const bool fused = by_compares && sten.present == 63 && use_avx2_kernel();
#endif
  parallel_for(nz, threads, [&](std::size_t z0, std::size_t z1) {
    detail::ThreadScratch<std::uint8_t> lbp(nx);
    detail::ThreadScratch<std::uint16_t> lvl(nx);
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        if (lbp_scratch) {  // the LBP codes are there: no map reads
          // The parked steps and LBP codes four rows on: the hardware prefetchers stop at each
          // 4 KB page (texture 25.4 -> 24.4 ms on the scene, one thread).
          if (y + 4 < ny) {
            const std::size_t ahead = nx * (y + 4 + ny * z);
            prefetch_row(codes + ahead, nx * sizeof(detail::code_t));
            prefetch_row(lbp_scratch + ahead, nx);
          }
          std::size_t x0 = 0, x1 = 0;
          if (!interior_row(d, y, z, x0, x1)) continue;
          const std::size_t at = nx * (y + ny * z) + x0;
          std::size_t n = x1 - x0;
          detail::code_t* row = codes + at;
          std::size_t done = 0;
#ifdef OCCSEG_TEXTURE_AVX2
          if (by_compares && use_avx2_kernel())
            done = use_avx512_kernel() ? codes_from_lbp_avx512(row, lbp_scratch + at, n, rises.data(), rises.size(),
                                                               static_cast<std::uint16_t>(contrast_bins))
                                       : codes_from_lbp_avx2(row, lbp_scratch + at, n, rises.data(), rises.size(),
                                       static_cast<std::uint16_t>(contrast_bins));
#endif
          row += done;
          n -= done;
          if (by_compares) {
            levels_row(row, n, rises.data(), rises.size(), lvl.data());
          } else {
            for (std::size_t x = 0; x < n; ++x) lvl[x] = level[row[x]];
          }
          combine_row(lbp_scratch + at + done, lvl.data(), n, static_cast<std::uint16_t>(contrast_bins), row);
          continue;
        }
        if (z + 2 < nz) prefetch_row(p + nx * (y + ny * (z + 2)), nx * sizeof(float));
        std::size_t x0 = 0, x1 = 0;
        if (!interior_row(d, y, z, x0, x1)) continue;
        detail::code_t* row = codes + nx * (y + ny * z) + x0;
        const float* prow = p + nx * (y + ny * z) + x0;
        std::size_t n = x1 - x0;
#ifdef OCCSEG_TEXTURE_AVX2
        if (fused) {
          const std::size_t done = codes_row_avx2(prow, sten.off, n, rises.data(), rises.size(),
                                                  static_cast<std::uint16_t>(contrast_bins), row);
          row += done, prow += done, n -= done;
        }
#endif
        lbp_any<0>(prow, sten.off, n, lbp.data(), sten.present);
        if (by_compares) {
          levels_row(row, n, rises.data(), rises.size(), lvl.data());
        } else {
          for (std::size_t x = 0; x < n; ++x) lvl[x] = level[row[x]];
        }
        combine_row(lbp.data(), lvl.data(), n, static_cast<std::uint16_t>(contrast_bins), row);
      }
  });
}

}  // namespace occseg
