// A table of byte shuffles (internal) that packs the 16-bit lanes picked by an 8-bit mask to the
// front of a vector, in order: SSSE3's pshufb, for processors without AVX-512 VBMI2's compress.
// Used by the AVX2 kernels of the texture (the fine steps of textured voxels) and of the division
// (the codes other than a block's common one), both to count only what is left after one vector
// test; the division's AVX2 listing of non-zero counts takes 32-bit lane indices for vpermd from
// it too (the entry for lane j holds 2j, 2j + 1). Plain C++: the table is data, built at start-up.
#pragma once
#include <cstdint>

namespace occseg::detail {

struct LanePackTable {
  alignas(16) std::uint8_t shuffle[256][16];
  LanePackTable() {
    for (int m = 0; m < 256; ++m) {
      int p = 0;
      for (int j = 0; j < 8; ++j)
        if (m & (1 << j)) {
          shuffle[m][2 * p] = static_cast<std::uint8_t>(2 * j);
          shuffle[m][2 * p + 1] = static_cast<std::uint8_t>(2 * j + 1);
          ++p;
        }
      for (; p < 8; ++p) shuffle[m][2 * p] = shuffle[m][2 * p + 1] = 0x80;
    }
  }
};

// One table for the whole library (4 KB).
inline const LanePackTable kLanePack;

}  // namespace occseg::detail
