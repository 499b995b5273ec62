// The default rules' kernels in AVX-512 F and BW (kernels/rules.hpp), 64 voxels per step.
#include "kernels/rules.hpp"

#include "rules/voxel_rules.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

namespace occseg::kernels::avx512 {

// The bit words are the blend and compare masks themselves, so nothing is spread into bytes; the
// last n % 64 voxels are one masked step. The result's bit rows are its compare masks.
__attribute__((target("avx512f,avx512bw"))) void rules_row(std::uint8_t* st, const word_t* u, const word_t* o,
                                                           const word_t* reg, const word_t* t, std::size_t n,
                                                           std::size_t first, std::vector<std::size_t>& seeds,
                                                           word_t* f, word_t* un, word_t* oc) {
  const __m512i unk = _mm512_set1_epi8(static_cast<char>(rules::kUnknown));
  const __m512i fre = _mm512_set1_epi8(static_cast<char>(rules::kFree));
  const __m512i occ = _mm512_set1_epi8(static_cast<char>(rules::kOccupied));
  for (std::size_t i = 0; 64 * i < n; ++i) {
    const std::size_t x = 64 * i;
    const __mmask64 in = n - x >= 64 ? ~__mmask64(0) : (__mmask64(1) << (n - x)) - 1;
    const __m512i s = _mm512_maskz_loadu_epi8(in, st + x);
    const __mmask64 gap = _mm512_cmpeq_epi8_mask(s, fre) & t[i];             // free, touching: unknown
    const __m512i res_unknown = _mm512_mask_mov_epi8(s, reg[i] | gap, unk);  // own state unknown
    const __m512i res = _mm512_mask_blend_epi8(u[i], _mm512_maskz_mov_epi8(o[i], occ), res_unknown);
    _mm512_mask_storeu_epi8(st + x, in, res);
    const std::uint64_t res_unknown_bits = _mm512_cmpeq_epi8_mask(res, unk) & in;
    if (f) {
      f[i] = _mm512_cmpeq_epi8_mask(res, fre) & in;
      un[i] = res_unknown_bits;
      oc[i] = _mm512_cmpeq_epi8_mask(res, occ) & in;
    }
    std::uint64_t m = u[i] & ~reg[i] & t[i] & res_unknown_bits;
    for (; m; m &= m - 1) seeds.push_back(first + x + static_cast<std::size_t>(__builtin_ctzll(m)));
  }
}

}  // namespace occseg::kernels::avx512
#endif
