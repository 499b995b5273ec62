// Bit rows (util/bit_rows.hpp) to and from AVX2 vectors of bytes, for kernels that checked the
// processor (x86-64 only).
#pragma once
#include <cstddef>
#include <cstdint>

#include "util/aliasing.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

namespace occseg::detail {

// The 32 bits of m as 32 bytes, 0xFF where set (byte i: bit i).
__attribute__((target("avx2"))) inline __m256i bytes_of_mask32(std::uint32_t m) {
  const __m256i b = _mm256_set1_epi32(static_cast<int>(m));
  // byte i of the result takes byte i / 8 of the 32 bits (a shuffle stays within 128-bit halves,
  // each of which holds all four)
  const __m256i pick = _mm256_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2, 3, 3,
                                        3, 3, 3, 3, 3, 3);
  const __m256i sel = _mm256_set1_epi64x(static_cast<long long>(0x8040201008040201ull));
  return _mm256_cmpeq_epi8(_mm256_and_si256(_mm256_shuffle_epi8(b, pick), sel), sel);
}

// Bits x .. x + 31 of a bit row as 32 bytes, 0xFF where set. The bits may straddle two words;
// the second is read only then (it lies in the row while x + 31 is in it).
__attribute__((target("avx2"))) inline __m256i bytes_of_bits32(const word_t* bits, std::size_t x) {
  std::uint64_t w = bits[x / 64] >> (x % 64);
  if (x % 64 > 32) w |= bits[x / 64 + 1] << (64 - x % 64);
  return bytes_of_mask32(static_cast<std::uint32_t>(w));
}

// Sets bits x .. x + 31 of a bit row (x a multiple of 32) where the bytes of `set` are 0xFF.
__attribute__((target("avx2"))) inline void set_bits32(word_t* bits, std::size_t x, __m256i set) {
  bits[x / 64] |= static_cast<std::uint64_t>(static_cast<std::uint32_t>(_mm256_movemask_epi8(set))) << (x % 64);
}

}  // namespace occseg::detail
#endif
