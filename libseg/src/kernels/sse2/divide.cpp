// The division's SSE2 kernels (the x86-64 baseline): counting that adds runs of equal codes at
// once, and the listing of non-zero counts by a compare per 16 bins.
#include "kernels/divide_levels.hpp"

#ifdef __SSE2__
#include <emmintrin.h>

#include "kernels/generic/divide_loops.hpp"
#include "util/thread_scratch.hpp"

namespace occseg::kernels::sse2 {

namespace {

// h[i] += a[i] + b[i], then a and b cleared: the extra histograms of count_rows folded back.
void fold_banks(std::uint32_t* __restrict h, std::uint32_t* __restrict a, std::uint32_t* __restrict b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    h[i] += a[i] + b[i];
    a[i] = b[i] = 0;
  }
}

// SkipNone = false: the block holds no kNoTexture voxel, so its voxels are counted without
// testing each.
template <bool SkipNone>
void count_rows(const code_t* codes, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h) {
  for (std::size_t i = 0; i < bins; ++i) h[i] = 0;
  // Rows that are not uniform count their voxels into three interleaved histograms (x mod 3):
  // such a row is mostly one code with a few others, and one histogram chained the increments
  // of that code (each waiting for the previous store). The two extra histograms live per thread
  // and are added and cleared only when a row used them.
  thread_local detail::ThreadScratch<std::uint32_t> extra;
  if (extra.size() < 2 * bins) extra.resize(2 * bins, 0u);
  std::uint32_t* const h1 = extra.data();
  std::uint32_t* const h2 = h1 + bins;
  bool used = false;
  const std::size_t nx = dims.nx, ny = dims.ny;
  std::uint32_t* const bank[3] = {h, h1, h2};
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z) {
    std::uint32_t y = b.lo[1];
    // Two rows at a time: 16 equal codes in one add, one test (and one branch) per two rows.
    for (; y + 1 < b.hi[1]; y += 2) {
      const code_t* r0 = codes + nx * (y + ny * z);
      const code_t* r1 = r0 + nx;
      std::uint32_t x = b.lo[0];
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m128i c = _mm_set1_epi16(static_cast<short>(r0[x]));
        const __m128i e0 = _mm_cmpeq_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + x)), c);
        const __m128i e1 = _mm_cmpeq_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r1 + x)), c);
        if (_mm_movemask_epi8(_mm_and_si128(e0, e1)) == 0xFFFF) {
          if (!SkipNone || r0[x] != kNoTexture) h[r0[x]] += 16;
          continue;
        }
        used = true;
        for (int k = 0; k < 8; ++k)
          if (!SkipNone || r0[x + k] != kNoTexture) ++bank[k % 3][r0[x + k]];
        for (int k = 0; k < 8; ++k)
          if (!SkipNone || r1[x + k] != kNoTexture) ++bank[(k + 1) % 3][r1[x + k]];
      }
      for (; x < b.hi[0]; ++x) {
        if (!SkipNone || r0[x] != kNoTexture) ++h[r0[x]];
        if (!SkipNone || r1[x] != kNoTexture) ++h[r1[x]];
      }
    }
    for (; y < b.hi[1]; ++y) {  // the last row of an odd count
      const code_t* row = codes + nx * (y + ny * z);
      std::uint32_t x = b.lo[0];
      // Eight equal codes (uniform texture: most rows of most maps) in one add.
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
        if (_mm_movemask_epi8(_mm_cmpeq_epi16(v, _mm_set1_epi16(static_cast<short>(row[x])))) == 0xFFFF) {
          if (!SkipNone || row[x] != kNoTexture) h[row[x]] += 8;
          continue;
        }
        used = true;
        const code_t* r = row + x;
        for (int k = 0; k < 8; ++k)
          if (!SkipNone || r[k] != kNoTexture) ++bank[k % 3][r[k]];
      }
      generic::count_run<SkipNone>(row, x, b.hi[0], h);
    }
  }
  if (used) fold_banks(h, h1, h2, bins);
}

// Bit j of the result set when v[j] != 0, for 16 values.
inline unsigned nonzero16(const std::uint32_t* v) {
  const __m128i zero = _mm_setzero_si128();
  const __m128i* c = reinterpret_cast<const __m128i*>(v);
  const __m128i a = _mm_packs_epi32(_mm_cmpeq_epi32(_mm_loadu_si128(c), zero), _mm_cmpeq_epi32(_mm_loadu_si128(c + 1), zero));
  const __m128i b = _mm_packs_epi32(_mm_cmpeq_epi32(_mm_loadu_si128(c + 2), zero), _mm_cmpeq_epi32(_mm_loadu_si128(c + 3), zero));
  return ~static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(a, b))) & 0xFFFFu;
}

// Two: the values of a + b, summed 16 at a time into `sum` first.
template <bool Two>
std::size_t list_nonzero(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out) {
  std::size_t m = 0, i = 0;
  alignas(16) std::uint32_t sum[16];
  const std::size_t whole = n & ~std::size_t(15);  // (then the tail one by one)
  for (; i < whole; i += 16) {
    const std::uint32_t* v = a + i;
    if (Two) {
      for (int k = 0; k < 16; k += 4)
        _mm_store_si128(reinterpret_cast<__m128i*>(sum + k),
                        _mm_add_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + i + k)),
                                      _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + i + k))));
      v = sum;
    }
    for (unsigned u = nonzero16(v); u; u &= u - 1) out[m++] = v[__builtin_ctz(u)];
  }
  for (; i < n; ++i) {
    const std::uint32_t v = Two ? a[i] + b[i] : a[i];
    if (v != 0) out[m++] = v;
  }
  return m;
}

}  // namespace

void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h) {
  if (in.may_lack_texture)
    count_rows<true>(in.codes, in.dims, in.b, bins, h);
  else
    count_rows<false>(in.codes, in.dims, in.b, bins, h);
}

std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out) {
  return b ? list_nonzero<true>(a, b, n, out) : list_nonzero<false>(a, nullptr, n, out);
}

}  // namespace occseg::kernels::sse2

#endif
