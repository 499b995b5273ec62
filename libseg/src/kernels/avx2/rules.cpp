// The default rules' kernels in AVX2 (kernels/rules.hpp), 32 voxels per step.
#include <algorithm>

#include "kernels/generic/rules_loops.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/avx2/bit_rows.hpp"

namespace occseg::kernels::avx2 {

namespace {

// voxel_rule() on voxels x .. x + 31 of a row, in place, from bit rows as in rules_row(); returns
// the gap seeds among them (0xFF).
__attribute__((target("avx2"))) inline __m256i rules_step(std::uint8_t* st, const word_t* u, const word_t* o,
                                                          const word_t* reg, const word_t* t, std::size_t x) {
  const __m256i unk = _mm256_set1_epi8(static_cast<char>(rules::kUnknown));
  const __m256i fre = _mm256_set1_epi8(static_cast<char>(rules::kFree));
  const __m256i occ = _mm256_set1_epi8(static_cast<char>(rules::kOccupied));
  __m256i* const at = reinterpret_cast<__m256i*>(st + x);
  const __m256i s = _mm256_loadu_si256(at);
  const __m256i own_unknown = detail::bytes_of_bits32(u, x), region = detail::bytes_of_bits32(reg, x);
  const __m256i touches = detail::bytes_of_bits32(t, x);
  const __m256i known = _mm256_and_si256(detail::bytes_of_bits32(o, x), occ);  // free (0) or occupied
  const __m256i gap = _mm256_blendv_epi8(s, unk, _mm256_and_si256(_mm256_cmpeq_epi8(s, fre), touches));
  const __m256i res = _mm256_blendv_epi8(known, _mm256_blendv_epi8(gap, unk, region), own_unknown);
  _mm256_storeu_si256(at, res);
  const __m256i gap_touching = _mm256_andnot_si256(region, _mm256_and_si256(own_unknown, touches));
  return _mm256_and_si256(gap_touching, _mm256_cmpeq_epi8(res, unk));
}

}  // namespace

// Rows of 32 voxels or more, 32 per step; the last step overlaps the one before instead of a
// scalar tail (the rules are idempotent: applied to their result they give it again), and only
// its new voxels' seeds are taken. The seeds come out of the same steps: a superset of them
// (before the touching bits) sent most rows through a scalar search. Shorter rows: the plain loop.
__attribute__((target("avx2"))) void rules_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg,
                                               const word_t* t, std::size_t n, std::size_t first,
                                               std::vector<std::size_t>& seeds) {
  if (n < 32) {
    generic::rules_row(st, u, o, reg, t, n, first, seeds);
    return;
  }
  // Steps at x0 = 0, 32, ... and, for the last n % 32 voxels, at n - 32, whose seeds below
  // `done` (bit k: voxel x0 + k) the step before reported already. (No lambda: it would not be
  // compiled for AVX2.)
  for (std::size_t done = 0; done < n;) {
    const std::size_t x0 = std::min(done, n - 32);
    auto m = static_cast<std::uint32_t>(_mm256_movemask_epi8(rules_step(st, u, o, reg, t, x0)));
    if (done > x0) m &= ~0u << (done - x0);
    for (; m; m &= m - 1) seeds.push_back(first + x0 + static_cast<std::size_t>(__builtin_ctz(m)));
    done = x0 + 32;
  }
}

}  // namespace occseg::kernels::avx2
#endif
