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
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
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

#if defined(__x86_64__) && defined(__GNUC__)
// AVX2, for callers that checked the processor. Bits x .. x + 31 of a bit row as 32 bytes, 0xFF
// where set. The bits may straddle two words; the second is read only then (it lies in the row
// while x + 31 is in it).
__attribute__((target("avx2"))) inline __m256i bytes_of_bits32(const word_t* bits, std::size_t x) {
  std::uint64_t w = bits[x / 64] >> (x % 64);
  if (x % 64 > 32) w |= bits[x / 64 + 1] << (64 - x % 64);
  const __m256i b = _mm256_set1_epi32(static_cast<int>(static_cast<std::uint32_t>(w)));
  // byte i of the result takes byte i / 8 of the 32 bits (a shuffle stays within 128-bit halves,
  // each of which holds all four)
  const __m256i pick = _mm256_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2, 3, 3,
                                        3, 3, 3, 3, 3, 3);
  const __m256i sel = _mm256_set1_epi64x(static_cast<long long>(0x8040201008040201ull));
  return _mm256_cmpeq_epi8(_mm256_and_si256(_mm256_shuffle_epi8(b, pick), sel), sel);
}

// Sets bits x .. x + 31 of a bit row (x a multiple of 32) where the bytes of `set` are 0xFF.
__attribute__((target("avx2"))) inline void set_bits32(word_t* bits, std::size_t x, __m256i set) {
  bits[x / 64] |= static_cast<std::uint64_t>(static_cast<std::uint32_t>(_mm256_movemask_epi8(set))) << (x % 64);
}
#endif

// The bit row of bytes[0, n) == v (the words cleared first; bits past n 0). SSE2 16 bytes at a
// time where it exists (every x86-64).
inline void pack_equal(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits) {
  for (std::size_t i = 0; i < (n + 63) / 64; ++i) bits[i] = 0;
  std::size_t x = 0;
#ifdef __SSE2__
  const __m128i vv = _mm_set1_epi8(static_cast<char>(v));
  for (; x + 16 <= n; x += 16)
    set_bits16(bits, x, _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes + x)), vv));
#endif
  for (; x < n; ++x) bits[x / 64] |= static_cast<std::uint64_t>(bytes[x] == v) << (x % 64);
}

#if defined(__x86_64__) && defined(__GNUC__)
// pack_equal() 32 bytes at a time (AVX2, for callers that checked the processor).
__attribute__((target("avx2"))) inline void pack_equal_avx2(const std::uint8_t* bytes, std::size_t n, std::uint8_t v,
                                                            word_t* bits) {
  for (std::size_t i = 0; i < (n + 63) / 64; ++i) bits[i] = 0;
  const __m256i vv = _mm256_set1_epi8(static_cast<char>(v));
  std::size_t x = 0;
  for (; x + 32 <= n; x += 32)
    set_bits32(bits, x, _mm256_cmpeq_epi8(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(bytes + x)), vv));
  for (; x < n; ++x) bits[x / 64] |= static_cast<std::uint64_t>(bytes[x] == v) << (x % 64);
}
#endif

}  // namespace occseg::detail
