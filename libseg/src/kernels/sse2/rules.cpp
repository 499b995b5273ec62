// The default rules' kernels in SSE2 (kernels/rules.hpp), 16 voxels per step: the x86-64 baseline.
#include "kernels/rules.hpp"

#include "rules/voxel_rules.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>

#include "kernels/sse2/bit_rows.hpp"

namespace occseg::kernels::sse2 {

void unpack_half(const word_t* bits, const std::uint8_t* own, std::size_t nx, std::uint8_t* out) {
  std::size_t x = 0;
  const __m128i one = _mm_set1_epi8(1), half = _mm_set1_epi8(static_cast<char>(rules::kUnknown));
  for (; x + 16 <= nx; x += 16) {
    const __m128i set = detail::bytes_of_bits16(bits, x);
    const __m128i is_half = _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(own + x)), half);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm_and_si128(_mm_and_si128(set, is_half), one));
  }
  for (; x < nx; ++x)
    out[x] = static_cast<std::uint8_t>(((bits[x / 64] >> (x % 64)) & 1) & (own[x] == rules::kUnknown));
}

}  // namespace occseg::kernels::sse2
#endif
