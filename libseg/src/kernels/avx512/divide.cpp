// The division's AVX-512 kernels: counting that packs the codes other than a block's common ones
// with VBMI2's 16-bit compress, and the listing of non-zero counts by a 32-bit compress.
#include "kernels/divide_levels.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include <algorithm>

#include "kernels/generic/divide_loops.hpp"

namespace occseg::kernels::avx512 {

namespace {

// avx2::count_packed for two rows at a time (four where the block is 8 wide): 16 voxels (8 of
// each row) in one 256-bit vector, the codes other than `common` (and, with Second, `second`)
// packed by one compress instruction.
#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // GCC 12 inside its own AVX-512 intrinsics
#endif
template <bool SkipNone, bool Second>
__attribute__((target("avx512f,avx512bw,avx512vl,avx512vbmi2,popcnt"))) void count_compress(
    const code_t* codes, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h, code_t common,
    code_t second) {
  std::fill(h, h + bins, 0u);
  std::uint16_t* const list = generic::code_list(b.volume() + 32);
  std::uint64_t same2 = 0;
  const __m512i second_code4 = _mm512_set1_epi16(static_cast<short>(second));
  const __m256i same_code = _mm256_set1_epi16(static_cast<short>(common));
  const __m256i none = _mm256_set1_epi16(static_cast<short>(kNoTexture));
  std::size_t len = 0;
  std::uint64_t same = 0;
  const std::size_t nx = dims.nx, ny = dims.ny;
  const bool eight_wide = b.hi[0] - b.lo[0] == 8;  // the division's Smin blocks inside the map
  const __m512i same_code4 = _mm512_set1_epi16(static_cast<short>(common));
  const __m512i none4 = _mm512_set1_epi16(static_cast<short>(kNoTexture));
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z) {
    std::uint32_t y = b.lo[1];
    // Rows of 8 voxels four at a time: one 512-bit compare, compress and store per 32 voxels.
    if (eight_wide)
      for (; y + 3 < b.hi[1]; y += 4) {
        const code_t* r0 = codes + nx * (y + ny * z) + b.lo[0];
        __m512i v = _mm512_castsi128_si512(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r0)));
        v = _mm512_inserti32x4(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + nx)), 1);
        v = _mm512_inserti32x4(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + 2 * nx)), 2);
        v = _mm512_inserti32x4(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + 3 * nx)), 3);
        const __mmask32 eq = _mm512_cmpeq_epi16_mask(v, same_code4);
        const __mmask32 eq2 = Second ? _mm512_mask_cmpeq_epi16_mask(static_cast<__mmask32>(~eq), v, second_code4) : 0;
        const auto other = static_cast<__mmask32>(~(eq | eq2));
        const __mmask32 keep = SkipNone ? static_cast<__mmask32>(other & _mm512_cmpneq_epi16_mask(v, none4)) : other;
        same += static_cast<unsigned>(__builtin_popcount(eq));
        if (Second) same2 += static_cast<unsigned>(__builtin_popcount(eq2));
        _mm512_storeu_si512(list + len, _mm512_maskz_compress_epi16(keep, v));
        len += static_cast<unsigned>(__builtin_popcount(keep));
      }
    for (; y + 1 < b.hi[1]; y += 2) {
      const code_t* r0 = codes + nx * (y + ny * z);
      const code_t* r1 = r0 + nx;
      std::uint32_t x = b.lo[0];
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m256i v = _mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(r1 + x),
                                              reinterpret_cast<const __m128i*>(r0 + x));
        const __mmask16 eq = _mm256_cmpeq_epi16_mask(v, same_code);
        const __mmask16 keep = SkipNone ? static_cast<__mmask16>(~eq & _mm256_cmpneq_epi16_mask(v, none))
                                        : static_cast<__mmask16>(~eq);
        same += static_cast<unsigned>(__builtin_popcount(eq));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(list + len), _mm256_maskz_compress_epi16(keep, v));
        len += static_cast<unsigned>(__builtin_popcount(keep));
      }
      generic::count_run<SkipNone>(r0, x, b.hi[0], h);
      generic::count_run<SkipNone>(r1, x, b.hi[0], h);
    }
    for (; y < b.hi[1]; ++y)  // an odd row count
      generic::count_run<SkipNone>(codes + nx * (y + ny * z), b.lo[0], b.hi[0], h);
  }
  generic::add_listed<SkipNone>(h, list, len, common, same);
  if (Second) h[second] += static_cast<std::uint32_t>(same2);
}
#pragma GCC diagnostic pop

template <bool Two>
__attribute__((target("avx512f,popcnt"))) std::size_t list_nonzero(const std::uint32_t* a, const std::uint32_t* b,
                                                                  std::size_t n, std::uint32_t* out) {
  std::size_t m = 0, i = 0;
  const std::size_t whole = n & ~std::size_t(15);  // (then the tail one by one)
  for (; i < whole; i += 16) {
    __m512i v = _mm512_loadu_si512(a + i);
    if (Two) v = _mm512_add_epi32(v, _mm512_loadu_si512(b + i));
    const __mmask16 k = _mm512_test_epi32_mask(v, v);
    _mm512_storeu_si512(out + m, _mm512_maskz_compress_epi32(k, v));
    m += static_cast<unsigned>(__builtin_popcount(k));
  }
  for (; i < n; ++i) {
    const std::uint32_t v = Two ? a[i] + b[i] : a[i];
    if (v != 0) out[m++] = v;
  }
  return m;
}

}  // namespace

// count_compress's instantiations as a class template, for generic::count_with_hints.
template <bool SkipNone, bool Second>
struct CountKernel {
  static void count(const code_t* codes, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h,
                    code_t common, code_t second) {
    count_compress<SkipNone, Second>(codes, dims, b, bins, h, common, second);
  }
};

void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h) { generic::count_with_hints<CountKernel>(in, bins, h); }

std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out) {
  return b ? list_nonzero<true>(a, b, n, out) : list_nonzero<false>(a, nullptr, n, out);
}

}  // namespace occseg::kernels::avx512

#endif
