// The texture kernels in AVX2 (kernels/texture.hpp): hand-written where the compiler's code was
// slower, the plain loops of generic/texture_loops.hpp compiled for AVX2 for the others.
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/generic/texture_loops.hpp"
#include "kernels/avx2/lane_pack.hpp"
#include "kernels/texture_impl.hpp"

namespace occseg::kernels::avx2 {

__attribute__((target("avx2"))) bool values_in_range(const float* p, std::size_t n) {
  return generic::values_in_range(p, n);
}

// generic::contrast_row<63>'s steps, 8 voxels per step. The float contrast is computed
// differently (the six masked neighbours summed as a tree of pairs, each mean as
// sum * fl(1 / count) with the reciprocal looked up by count): shorter dependency chains and no
// divisions. The certificate still holds: a sum of at most six floats in [0, 1] in any order is
// within 5u * sum of the exact sum (u = 2^-24), the rounded reciprocal and the product add 2u, so
// each mean is within 7u <= 4.2e-7 of its exact value, the difference within 8.4e-7 + u * |c| <
// 9e-7 of the double contrast, and c +- 1e-6 (each bound rounded by at most 6e-8) still encloses
// it. So the sure steps are texture_unit()'s, as are the kRecheckStep voxels', whichever kernel
// ran. No FMA in the interval itself: it would change the rounding the bound accounts for.
//
// With `lbp` (else nullptr), the voxels' LBP codes go there too, from the same comparisons.
//
// The row's values are checked here too, as the centres are loaded (no separate pass over the
// map for the check): returns false when one of p[0..n) is not in [0, 1] (NaN included). The
// arithmetic above is defined for any float (the conversions of NaN or huge values give INT_MIN,
// below every step).
//
// Rows of 8 voxels or more end with a step that overlaps the one before (its voxels' results
// depend on the map only) instead of a scalar tail, which would cost as much as many vector
// steps. `maybe_recheck` is set exactly when some voxel is kRecheckStep (no scan of the row).
__attribute__((target("avx2"))) bool contrast_row(const float* p, const std::ptrdiff_t* off, std::size_t n,
                                                  code_t* out, std::uint8_t* lbp, bool& maybe_recheck) {
  if (n < 8) {
    generic::contrast_row<63, true>(p, off, n, out);
    if (lbp) generic::lbp_row<63>(p, off, n, lbp);
    maybe_recheck = std::find(out, out + n, kRecheckStep) != out + n;
    return generic::values_in_range(p, n);
  }
  __m256i rc = _mm256_setzero_si256();
  const __m256 zero = _mm256_setzero_ps(), err = _mm256_set1_ps(1e-6f), one = _mm256_set1_ps(1.0f);
  __m256 bad = zero;
  const __m256 fine = _mm256_set1_ps(static_cast<float>(ContrastQuantizer::kFine));
  const __m256i top = _mm256_set1_epi32(ContrastQuantizer::kFine - 1), recheck = _mm256_set1_epi32(kRecheckStep);
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
  maybe_recheck = !_mm256_testz_si256(rc, rc);
  return _mm256_testz_ps(bad, bad);
}

__attribute__((target("avx2"))) bool any_recheck(const code_t* steps, std::size_t n) {
  return generic::any_recheck(steps, n);
}

// The non-zero steps of 8 voxels at a time are packed to the front of a vector (a table of
// shuffles indexed by the non-zero mask) and appended to `list`, and only they are counted: no
// branch per group, where textured voxels scattered among flat ones would mispredict
// scalar::count_steps's "are these four all flat?".
__attribute__((target("avx2"))) void count_steps(const code_t* v, std::size_t n, std::uint64_t* h,
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
  generic::count_list(list, len, h);
}

// Pass 2 from the map, 8 voxels per step, in place: row[x] = lbp * bins + level, from the parked
// step v = row[x] and the six comparisons of the LBP code (the same `>=` as generic::lbp_row).
// One pass instead of three over the row (LBP codes, levels, combination). Returns the voxels
// done (a multiple of 8); the caller finishes the row.
__attribute__((target("avx2"))) std::size_t codes_row(const float* p, const std::ptrdiff_t* off, std::size_t n,
                                                      const std::uint16_t* rises, std::size_t nr, std::uint16_t bins,
                                                      code_t* row) {
  __m256i rise[16];
  for (std::size_t k = 0; k < nr; ++k) rise[k] = _mm256_set1_epi32(rises[k]);
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi32(1);
  // Bit k of the LBP code weighs bins << k, and the weights are added: the code comes out
  // multiplied by bins (no multiply).
  __m256i weight[6];
  for (int k = 0; k < 6; ++k) weight[k] = _mm256_set1_epi32(bins << k);
  const std::ptrdiff_t o[6] = {off[0], off[1], off[2], off[3], off[4], off[5]};  // see contrast_row
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
// the level from the parked step v = row[x] as in codes_row (steps <= 4096 compare as signed
// 16-bit values).
__attribute__((target("avx2"))) void codes_from_lbp(code_t* row, const std::uint8_t* lbp, std::size_t n,
                                                    const std::uint16_t* rises, std::size_t nr, std::uint16_t bins) {
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
}

__attribute__((target("avx2"))) void lbp_row(const float* p, const std::ptrdiff_t* off, std::size_t n,
                                             unsigned present, std::uint8_t* out) {
  if (present == 63) generic::lbp_row<63>(p, off, n, out);
  else scalar::lbp_row(p, off, n, present, out);  // (maps with an axis of size 1)
}

__attribute__((target("avx2"))) void levels_row(const code_t* v, std::size_t n, const std::uint16_t* rises,
                                                std::size_t nr, std::uint16_t* lvl) {
  generic::levels_row(v, n, rises, nr, lvl);
}

__attribute__((target("avx2"))) void combine_row(const std::uint8_t* lbp, const std::uint16_t* lvl, std::size_t n,
                                                 std::uint16_t bins, code_t* code) {
  generic::combine_row(lbp, lvl, n, bins, code);
}

}  // namespace occseg::kernels::avx2
#endif
