// Rows of voxels as bits (internal): 64 voxels of a row per word, voxel x at bit x % 64 of word
// x / 64, the bits past a row's end 0. The own states (stages/own_states.hpp), the opening of the
// default rules (departures.cpp) and the unknown growth (refine_unknown.cpp) keep such masks,
// possibly in the label array (segment()), so every access goes through word_t, which may alias
// that storage's type (util/aliasing.hpp). Vector forms are in kernels/sse2/bit_rows.hpp and
// kernels/avx2/bit_rows.hpp.
#pragma once
#include <cstddef>
#include <cstdint>

#include "util/aliasing.hpp"

namespace occseg::detail {

// The bit row of bytes[0, n) == v (the words cleared first; bits past n 0).
inline void pack_equal(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits) {
  for (std::size_t i = 0; i < (n + 63) / 64; ++i) bits[i] = 0;
  for (std::size_t x = 0; x < n; ++x) bits[x / 64] |= static_cast<std::uint64_t>(bytes[x] == v) << (x % 64);
}

}  // namespace occseg::detail
