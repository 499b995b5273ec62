// Rows of voxels as bits (internal): 64 voxels of a row per word, voxel x at bit x % 64 of word
// x / 64, the bits past a row's end 0. The opening of the default rules (departures.cpp) and the
// unknown growth (unknown_growth.cpp) keep such masks, possibly in the label array (segment()),
// so every access goes through word_t, which may alias that storage's type (see
// codes_internal.hpp).
#pragma once
#include <cstddef>
#include <cstdint>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace occseg::detail {

typedef std::uint64_t __attribute__((__may_alias__)) word_t;

#ifdef __SSE2__
// Bits x .. x + 15 of a bit row (x a multiple of 16, so they lie in one word) as 16 bytes, 0xFF
// where the bit is set.
inline __m128i bytes_of_bits16(const word_t* bits, std::size_t x) {
  const auto b = static_cast<std::uint16_t>(bits[x / 64] >> (x % 64));
  const __m128i sel = _mm_setr_epi8(1, 2, 4, 8, 16, 32, 64, -128, 1, 2, 4, 8, 16, 32, 64, -128);
  const __m128i spread = _mm_set_epi64x(static_cast<long long>((b >> 8) * 0x0101010101010101ull),
                                        static_cast<long long>((b & 0xFFu) * 0x0101010101010101ull));
  return _mm_cmpeq_epi8(_mm_and_si128(spread, sel), sel);
}

// Sets bits x .. x + 15 of a bit row (x a multiple of 16) where the bytes of `set` are 0xFF.
inline void set_bits16(word_t* bits, std::size_t x, __m128i set) {
  bits[x / 64] |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm_movemask_epi8(set))) << (x % 64);
}
#endif

}  // namespace occseg::detail
