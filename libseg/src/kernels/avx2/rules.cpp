// The default rules' kernels in AVX2 (kernels/rules.hpp): rows of 64 voxels or more 64 per step on
// bits, shorter ones 32 per step on bytes.
#include <algorithm>

#include "kernels/generic/rules_loops.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/avx2/bit_rows.hpp"

namespace occseg::kernels::avx2 {

namespace {

// voxel_rule() on voxels x .. x + 31 of a row, in place, from bit rows as in rules_row(); returns
// the gap seeds among them (0xFF), the result in `out`.
__attribute__((target("avx2"))) inline __m256i rules_step(std::uint8_t* st, const word_t* u, const word_t* o,
                                                          const word_t* reg, const word_t* t, std::size_t x,
                                                          __m256i& out) {
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
  out = res;
  const __m256i gap_touching = _mm256_andnot_si256(region, _mm256_and_si256(own_unknown, touches));
  return _mm256_and_si256(gap_touching, _mm256_cmpeq_epi8(res, unk));
}

// ORs the 32 bits `m` into a bit row at voxel x (any x: they may straddle two words).
inline void or_bits32(word_t* row, std::size_t x, std::uint32_t m) {
  const unsigned b = x % 64;
  row[x / 64] |= static_cast<std::uint64_t>(m) << b;
  if (b > 32) row[x / 64 + 1] |= static_cast<std::uint64_t>(m) >> (64 - b);
}

}  // namespace

// Rows of 32 voxels or more, 32 per step; the last step overlaps the one before instead of a
// scalar tail (the rules are idempotent: applied to their result they give it again), and only
// its new voxels' seeds are taken. The seeds come out of the same steps: a superset of them
// (before the touching bits) sent most rows through a scalar search. Shorter rows: the plain loop.
namespace {

// Rows of 32 to 63 voxels (and shorter: the plain loop).
__attribute__((target("avx2"))) void short_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg,
                                               const word_t* t, std::size_t n, std::size_t first,
                                               std::vector<std::size_t>& seeds, word_t* f, word_t* un, word_t* oc) {
  if (n < 32) {
    generic::rules_row(st, u, o, reg, t, n, first, seeds, f, un, oc);
    return;
  }
  if (f)
    for (std::size_t i = 0; i < (n + 63) / 64; ++i) f[i] = un[i] = oc[i] = 0;
  const __m256i occ = _mm256_set1_epi8(static_cast<char>(rules::kOccupied));
  const __m256i fre = _mm256_set1_epi8(static_cast<char>(rules::kFree));
  const __m256i unk = _mm256_set1_epi8(static_cast<char>(rules::kUnknown));
  // Steps at x0 = 0, 32, ... and, for the last n % 32 voxels, at n - 32, whose seeds below
  // `done` (bit k: voxel x0 + k) the step before reported already. (No lambda: it would not be
  // compiled for AVX2.)
  for (std::size_t done = 0; done < n;) {
    const std::size_t x0 = std::min(done, n - 32);
    __m256i res;
    auto m = static_cast<std::uint32_t>(_mm256_movemask_epi8(rules_step(st, u, o, reg, t, x0, res)));
    if (done > x0) m &= ~0u << (done - x0);
    for (; m; m &= m - 1) seeds.push_back(first + x0 + static_cast<std::size_t>(__builtin_ctz(m)));
    if (f) {  // (the overlapping last step's voxels get the same bits again)
      or_bits32(f, x0, static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(res, fre))));
      or_bits32(un, x0, static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(res, unk))));
      or_bits32(oc, x0, static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(res, occ))));
    }
    done = x0 + 32;
  }
}

// Bits x .. x + 63 of a bit row (x + 63 within the row: the second word is read only then).
inline std::uint64_t bits64_at(const word_t* row, std::size_t x) {
  const unsigned b = x % 64;
  const std::uint64_t v = row[x / 64] >> b;
  return b ? v | row[x / 64 + 1] << (64 - b) : v;
}

// ORs the 64 bits `m` into a bit row at voxel x (x + 63 within the row).
inline void or_bits64(word_t* row, std::size_t x, std::uint64_t m) {
  const unsigned b = x % 64;
  row[x / 64] |= m << b;
  if (b) row[x / 64 + 1] |= m >> (64 - b);
}

// The 64 bits of two compare results (0xFF bytes), a's first.
__attribute__((target("avx2"))) inline std::uint64_t mask(__m256i a, __m256i b) {
  return static_cast<std::uint64_t>(static_cast<std::uint32_t>(_mm256_movemask_epi8(a))) |
         static_cast<std::uint64_t>(static_cast<std::uint32_t>(_mm256_movemask_epi8(b))) << 32;
}

// 32 bytes: 1 where bit k of `unknown` is set, 2 where bit k of `occupied` is (never both).
__attribute__((target("avx2"))) inline __m256i state_bytes32(std::uint32_t unknown, std::uint32_t occupied) {
  const word_t w[2] = {unknown, occupied};
  const __m256i one = _mm256_set1_epi8(1), two = _mm256_set1_epi8(2);
  return _mm256_or_si256(_mm256_and_si256(detail::bytes_of_bits32(w, 0), one),
                         _mm256_and_si256(detail::bytes_of_bits32(w + 1, 0), two));
}

}  // namespace

// Rows of 64 voxels or more: 64 voxels per step, the rules on bits (voxel_rule() on masks: the
// states' bytes are read as two compare masks, free and unknown), written back as bytes only where
// a voxel's state changes (in most of a map the refined state is the own state already). The last
// n % 64 voxels: a step at n - 64 over the one before (the rules are idempotent), only its new
// voxels' seeds taken.
__attribute__((target("avx2"))) void rules_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg,
                                               const word_t* t, std::size_t n, std::size_t first,
                                               std::vector<std::size_t>& seeds, word_t* f, word_t* un, word_t* oc) {
  if (n < 64) {
    short_row(st, u, o, reg, t, n, first, seeds, f, un, oc);
    return;
  }
  const std::size_t W = (n + 63) / 64;
  if (f && n % 64)  // (the overlapping last step ORs into its words)
    for (std::size_t i = W - 2; i < W; ++i) f[i] = un[i] = oc[i] = 0;
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi8(1);
  for (std::size_t done = 0; done < n;) {
    const std::size_t x0 = std::min(done, n - 64);
    const __m256i s0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(st + x0));
    const __m256i s1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(st + x0 + 32));
    const std::uint64_t sf = mask(_mm256_cmpeq_epi8(s0, zero), _mm256_cmpeq_epi8(s1, zero));
    const std::uint64_t su = mask(_mm256_cmpeq_epi8(s0, one), _mm256_cmpeq_epi8(s1, one));
    const std::uint64_t so = ~(sf | su);
    const std::uint64_t U = bits64_at(u, x0), O = bits64_at(o, x0) & ~U, R = bits64_at(reg, x0),
                        T = bits64_at(t, x0);
    // voxel_rule(): own state known: it (rule 1); unknown in a region: unknown (rule 2); in a gap:
    // the refined state, free touching an occupied voxel made unknown (rule 3).
    const std::uint64_t ru = U & (R | su | (sf & T)), ro = O | (U & ~R & so), rf = ~(ru | ro);
    if ((ru ^ su) | (rf ^ sf)) {  // a state changed: the 32-voxel halves that hold one, rewritten
      const std::uint64_t changed = (ru ^ su) | (rf ^ sf);
      if (static_cast<std::uint32_t>(changed))
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(st + x0),
                            state_bytes32(static_cast<std::uint32_t>(ru), static_cast<std::uint32_t>(ro)));
      if (changed >> 32)
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(st + x0 + 32),
                            state_bytes32(static_cast<std::uint32_t>(ru >> 32), static_cast<std::uint32_t>(ro >> 32)));
    }
    std::uint64_t m = U & ~R & T & ru;  // gap_seed()
    if (done > x0) m &= ~std::uint64_t(0) << (done - x0);
    for (; m; m &= m - 1) seeds.push_back(first + x0 + static_cast<std::size_t>(__builtin_ctzll(m)));
    if (f) {
      if (x0 % 64 == 0) {
        f[x0 / 64] = rf;
        un[x0 / 64] = ru;
        oc[x0 / 64] = ro;
      } else {
        or_bits64(f, x0, rf);
        or_bits64(un, x0, ru);
        or_bits64(oc, x0, ro);
      }
    }
    done = x0 + 64;
  }
}

}  // namespace occseg::kernels::avx2
#endif
