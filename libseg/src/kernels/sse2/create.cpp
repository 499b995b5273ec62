// The create kernels in SSE2 (kernels/create.hpp), the x86-64 baseline.
#if defined(__x86_64__) && defined(__GNUC__)
#include <emmintrin.h>

#include "kernels/create_impl.hpp"
#include "kernels/sse2/bit_rows.hpp"

namespace occseg::kernels::sse2 {

// 1 + (p < lo ? -1 : 0) - (p > hi ? -1 : 0), eight voxels per step; NaN gives 1 (unknown), as in
// scalar::own_states.
void own_states(const float* p, std::size_t n, float lo, float hi, std::uint8_t* out) {
  std::size_t i = 0;
  const __m128 l = _mm_set1_ps(lo), h = _mm_set1_ps(hi);
  const __m128i one = _mm_set1_epi32(1);
  for (; i + 8 <= n; i += 8) {
    const __m128 a = _mm_loadu_ps(p + i), b = _mm_loadu_ps(p + i + 4);
    const __m128i sa = _mm_sub_epi32(_mm_add_epi32(one, _mm_castps_si128(_mm_cmplt_ps(a, l))),
                                     _mm_castps_si128(_mm_cmpgt_ps(a, h)));
    const __m128i sb = _mm_sub_epi32(_mm_add_epi32(one, _mm_castps_si128(_mm_cmplt_ps(b, l))),
                                     _mm_castps_si128(_mm_cmpgt_ps(b, h)));
    const __m128i s16 = _mm_packs_epi32(sa, sb);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + i), _mm_packus_epi16(s16, s16));
  }
  for (; i < n; ++i) out[i] = static_cast<std::uint8_t>(p[i] < lo ? 0 : (p[i] > hi ? 2 : 1));
}

void pack_equal(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits) {
  detail::pack_equal_sse2(bytes, n, v, bits);
}

}  // namespace occseg::kernels::sse2
#endif
