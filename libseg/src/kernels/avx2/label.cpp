// The labelling's AVX2 kernel: the run starts of a row, 32 voxels a step.
#include "kernels/label_levels.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

namespace occseg::kernels::avx2 {

namespace {

// Bits of voxels t .. t + 31 of `row` (t + 32 <= row length): where a voxel differs from the one
// before it; voxel 0 of the row (t = 0) is set.
__attribute__((target("avx2"))) inline std::uint32_t starts32(const std::uint8_t* row, std::size_t t) {
  const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + t));
  // t = 0: v shifted up by one byte (across the halves), a zero in byte 0
  const __m256i before = t ? _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + t - 1))
                           : _mm256_alignr_epi8(v, _mm256_permute2x128_si256(v, v, 0x08), 15);
  return ~static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(v, before))) | (t ? 0u : 1u);
}

inline void or_bytes(std::uint8_t* b, std::uint32_t m, std::size_t bytes) {
  for (std::size_t k = 0; k < bytes; ++k) b[k] = static_cast<std::uint8_t>(b[k] | (m >> (8 * k)));
}

}  // namespace

// As the SSE2 kernel, 32 voxels a step; rows shorter than 32 voxels go to it.
__attribute__((target("avx2"))) void label_row_starts(const std::uint8_t* row, std::size_t nx, std::uint8_t* bits,
                                                      std::size_t i0) {
  if (nx < 32) return sse2::label_row_starts(row, nx, bits, i0);
  std::size_t x = 0;
  if (i0 % 8) {
    bits[i0 / 8] = static_cast<std::uint8_t>(bits[i0 / 8] | (1u << (i0 % 8)));
    for (x = 1; (i0 + x) % 8; ++x)
      if (row[x] != row[x - 1])
        bits[(i0 + x) / 8] = static_cast<std::uint8_t>(bits[(i0 + x) / 8] | (1u << ((i0 + x) % 8)));
  }
  for (; x + 32 <= nx; x += 32) {
    const std::uint32_t m = starts32(row, x);
    std::uint8_t* b = bits + (i0 + x) / 8;
    std::uint32_t w;
    __builtin_memcpy(&w, b, sizeof w);
    w |= m;  // little-endian: bit k of m is bit k % 8 of byte k / 8
    __builtin_memcpy(b, &w, sizeof w);
  }
  if (x < nx)  // 1 to 31 voxels from a whole byte on
    or_bytes(bits + (i0 + x) / 8, starts32(row, nx - 32) >> (x - (nx - 32)), (nx - x + 7) / 8);
}

}  // namespace occseg::kernels::avx2

#endif
