// The division's AVX2 kernels: counting that packs the codes other than a block's common one to a
// list (a byte shuffle from the lane-packing table), the listing of non-zero counts by a permute,
// and the plain loops of generic/divide_loops.hpp compiled for AVX2.
#include "kernels/divide_levels.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include <algorithm>

#include "kernels/avx2/lane_pack.hpp"
#include "kernels/generic/divide_loops.hpp"

namespace occseg::kernels::avx2 {

namespace {

// In each 8 voxels of a row, the block's `common` code is counted with one compare and a
// popcount, and only the other codes are packed to the front of a vector and appended to a list,
// counted at the end: no branch per group of voxels. In a map whose flat code is most voxels but
// whose groups of eight are mostly not all flat (the built-in operator's codes of a real scene),
// a test "all eight equal?" is mostly false, and counting one by one after it is the slow case.
// With Second, voxels of a `second` code are counted by a compare too (it must differ from common).
template <bool SkipNone, bool Second>
__attribute__((target("avx2,popcnt"))) void count_packed(const code_t* codes, const Dims& dims, const Block& b,
                                                         std::size_t bins, std::uint32_t* h, code_t common,
                                                         code_t second) {
  std::fill(h, h + bins, 0u);
  std::uint16_t* const list = generic::code_list(b.volume() + 8);
  const __m128i same_code = _mm_set1_epi16(static_cast<short>(common));
  const __m128i second_code = _mm_set1_epi16(static_cast<short>(second));
  std::uint64_t same2 = 0;
  const __m128i none = _mm_set1_epi16(static_cast<short>(kNoTexture));
  std::size_t len = 0;
  std::uint64_t same = 0;
  const std::size_t nx = dims.nx, ny = dims.ny;
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
    for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y) {
      const code_t* row = codes + nx * (y + ny * z);
      std::uint32_t x = b.lo[0];
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
        const __m128i eq = _mm_cmpeq_epi16(v, same_code);
        // (second != common: no lane is in both)
        const __m128i eq2 = Second ? _mm_cmpeq_epi16(v, second_code) : _mm_setzero_si128();
        // Lanes not listed: the common code (and the second), and (SkipNone) voxels without texture.
        const __m128i counted = Second ? _mm_or_si128(eq, eq2) : eq;
        const __m128i skip = SkipNone ? _mm_or_si128(counted, _mm_cmpeq_epi16(v, none)) : counted;
        const unsigned e = static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(eq, eq))) & 0xFFu;
        if (Second)
          same2 += static_cast<unsigned>(__builtin_popcount(_mm_movemask_epi8(_mm_packs_epi16(eq2, eq2)) & 0xFF));
        const unsigned keep = ~static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(skip, skip))) & 0xFFu;
        same += static_cast<unsigned>(__builtin_popcount(e));
        const __m128i ctl = _mm_load_si128(reinterpret_cast<const __m128i*>(detail::kLanePack.shuffle[keep]));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(list + len), _mm_shuffle_epi8(v, ctl));
        len += static_cast<unsigned>(__builtin_popcount(keep));
      }
      generic::count_run<SkipNone>(row, x, b.hi[0], h);  // blocks cut by the map's edge
    }
  generic::add_listed<SkipNone>(h, list, len, common, same);
  if (Second) h[second] += static_cast<std::uint32_t>(same2);
}

template <bool Two>
__attribute__((target("avx2,popcnt"))) std::size_t list_nonzero(const std::uint32_t* a, const std::uint32_t* b,
                                                                std::size_t n, std::uint32_t* out) {
  std::size_t m = 0, i = 0;
  const __m256i zero = _mm256_setzero_si256();
  const std::size_t whole = n & ~std::size_t(7);  // (then the tail one by one)
  for (; i < whole; i += 8) {
    __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(a + i));
    if (Two) v = _mm256_add_epi32(v, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + i)));
    const unsigned k =
        ~static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(v, zero)))) & 0xFFu;
    // vpermd's lane indices from the 16-bit packing table: entry (2j, 2j + 1) shifted right by one
    // holds j in its low three bits, the only ones vpermd reads (unused entries 0x8080: lane 0).
    const __m128i pairs = _mm_load_si128(reinterpret_cast<const __m128i*>(detail::kLanePack.shuffle[k]));
    const __m256i idx = _mm256_cvtepu16_epi32(_mm_srli_epi16(pairs, 1));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + m), _mm256_permutevar8x32_epi32(v, idx));
    m += static_cast<unsigned>(__builtin_popcount(k));
  }
  for (; i < n; ++i) {
    const std::uint32_t v = Two ? a[i] + b[i] : a[i];
    if (v != 0) out[m++] = v;
  }
  return m;
}

}  // namespace

// count_packed's instantiations as a class template, for generic::count_with_hints.
template <bool SkipNone, bool Second>
struct CountKernel {
  static void count(const code_t* codes, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h,
                    code_t common, code_t second) {
    count_packed<SkipNone, Second>(codes, dims, b, bins, h, common, second);
  }
};

void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h) { generic::count_with_hints<CountKernel>(in, bins, h); }

std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out) {
  return b ? list_nonzero<true>(a, b, n, out) : list_nonzero<false>(a, nullptr, n, out);
}

__attribute__((target("avx2"))) std::uint64_t total(const std::uint32_t* h, std::size_t n) {
  return generic::total(h, n);
}

__attribute__((target("avx2"))) void sum_eight(std::uint32_t* h, const std::uint32_t* a, std::size_t stride,
                                               std::size_t n) {
  generic::sum_eight(h, a, stride, n);
}

__attribute__((target("avx2"))) void add_counts(std::uint32_t* h, const std::uint32_t* a, std::size_t n) {
  generic::add_counts(h, a, n);
}

}  // namespace occseg::kernels::avx2

#endif
