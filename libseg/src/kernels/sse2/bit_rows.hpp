// Bit rows (util/bit_rows.hpp) to and from SSE2 vectors of bytes, for kernels (x86-64 only).
#pragma once
#include <cstddef>
#include <cstdint>

#include "util/aliasing.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>

namespace occseg::detail {

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

// pack_equal() (util/bit_rows.hpp) 16 bytes at a time.
inline void pack_equal_sse2(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits) {
  for (std::size_t i = 0; i < (n + 63) / 64; ++i) bits[i] = 0;
  std::size_t x = 0;
  const __m128i vv = _mm_set1_epi8(static_cast<char>(v));
  for (; x + 16 <= n; x += 16)
    set_bits16(bits, x, _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes + x)), vv));
  for (; x < n; ++x) bits[x / 64] |= static_cast<std::uint64_t>(bytes[x] == v) << (x % 64);
}

}  // namespace occseg::detail
#endif
