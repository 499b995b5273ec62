// The refinement kernels' plain loops (kernels/refine.hpp), shared by the levels: scalar/ compiles
// them as they are, the vector levels take their tails from here and avx2/ compiles the whole-row
// tests under target("avx2") (the vectorisation is the compiler's). Every loop is always_inline,
// so that it is compiled for the target of the level's function that calls it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "kernels/refine.hpp"

namespace occseg::kernels::generic {

constexpr std::uint8_t kFree = 0, kUnknown = 1, kOccupied = 2;
// States are 0..2, so only a free/occupied pair differs by xor 2.
constexpr std::uint8_t kFreeXorOccupied = kFree ^ kOccupied;

__attribute__((always_inline)) inline bool any_boundary(const std::uint8_t* __restrict a,
                                                        const std::uint8_t* __restrict b, std::size_t n) {
  std::uint8_t any = 0;
  for (std::size_t x = 0; x < n; ++x) any |= static_cast<std::uint8_t>((a[x] ^ b[x]) == kFreeXorOccupied);
  return any != 0;
}

__attribute__((always_inline)) inline bool any_occupied(const std::uint8_t* s, std::size_t n) {
  std::uint8_t any = 0;
  for (std::size_t x = 0; x < n; ++x) any |= static_cast<std::uint8_t>(s[x] == kOccupied);
  return any != 0;
}

// next_boundary() from scan position k on, one pair at a time.
__attribute__((always_inline)) inline std::size_t next_boundary_from(const std::uint8_t* st, std::size_t k,
                                                                     std::size_t len, int step) {
  const auto pair = [&](std::size_t q) {
    const std::size_t j = step > 0 ? q : len - 1 - q;
    const std::size_t before = step > 0 ? j - 1 : j + 1;
    return ((st[before] ^ st[j]) & 3) == kFreeXorOccupied;
  };
  while (k < len && !pair(k)) ++k;
  return k;
}

// window_starts() for lanes [x, nx), appending to lanes[count...]; returns the new count.
__attribute__((always_inline)) inline std::size_t window_starts_from(const std::uint8_t* prev, const std::uint8_t* cur,
                                                                     std::uint8_t* skip, std::size_t x, std::size_t nx,
                                                                     std::uint32_t* lanes, std::size_t count) {
  for (; x < nx; ++x) {
    if (skip[x]) {
      --skip[x];
      continue;
    }
    if ((prev[x] ^ cur[x]) == kFreeXorOccupied) lanes[count++] = static_cast<std::uint32_t>(x);
  }
  return count;
}

// plane_row() for lanes [x, nx), 64 at a time (the lanes' list on the stack), into r: starts(b,
// e, lanes) lists the lanes of [b, e) that start a window (window_starts' rule, their skips
// counted down; absolute lane numbers, increasing) and returns how many; each such window is
// then decided on its own.
template <class Starts>
__attribute__((always_inline)) inline void lane_windows(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs,
                                                        int rows, std::uint8_t* skip, std::size_t x, std::size_t nx,
                                                        const word_t* const* occ, const word_t* const* unk,
                                                        Starts&& starts, PlaneRow& r) {
  std::uint32_t lanes[64];
  for (; x < nx; x += 64) {
    const std::size_t count = starts(x, nx - x < 64 ? nx : x + 64, lanes);
    r.started = r.started || count != 0;
    for (std::size_t j = 0; j < count; ++j) {
      const std::size_t l = lanes[j];
      std::uint8_t* const c = cur + l;
      int n = 1;  // the window's voxels: c[0] and those after it equal to it
      while (n < rows && c[n * rs] == c[0]) ++n;
      const std::size_t i = l / 64;
      const unsigned b = l % 64;
      const auto lane = [&](const word_t* const* w) {
        std::uint64_t m = 0;
        for (int k = 0; k < n; ++k) m |= ((w[k][i] >> b) & 1u) << k;
        return m;
      };
      const std::uint8_t from = prev[l];
      const std::uint64_t all = n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1;
      std::uint64_t moves = window_moves(lane(occ), all, from, [&] { return lane(unk); });
      if (from == kOccupied) r.occupied_rows |= moves;
      for (; moves; moves &= moves - 1) c[__builtin_ctzll(moves) * rs] = from;
      skip[l] = static_cast<std::uint8_t>(n - 1);
    }
  }
}

// lane_windows()' starts by the plain loop.
struct PlainStarts {
  const std::uint8_t* prev;
  const std::uint8_t* cur;
  std::uint8_t* skip;
  std::size_t operator()(std::size_t b, std::size_t e, std::uint32_t* lanes) const {
    return window_starts_from(prev, cur, skip, b, e, lanes, 0);
  }
};

// Bits [x, nx) of pack_states() (the words cleared already).
__attribute__((always_inline)) inline void pack_states_from(const std::uint8_t* st, std::size_t x, std::size_t nx,
                                                            word_t* unknown, word_t* free) {
  for (; x < nx; ++x) {
    unknown[x / 64] |= static_cast<std::uint64_t>(st[x] == kUnknown) << (x % 64);
    free[x / 64] |= static_cast<std::uint64_t>(st[x] == kFree) << (x % 64);
  }
}

__attribute__((always_inline)) inline void clear_words(word_t* bits, std::size_t n) {
  for (std::size_t i = 0; i < (n + 63) / 64; ++i) bits[i] = 0;
}

// Voxels [x, nx) of unpack_unknown().
__attribute__((always_inline)) inline void unpack_unknown_from(const word_t* w, std::size_t x, std::size_t nx,
                                                               std::uint8_t* st) {
  for (; x < nx; ++x)
    if ((w[x / 64] >> (x % 64)) & 1u) st[x] = kUnknown;
}

// Byte i of the result 0xFF where bit i of b (i < 8) is set, else 0.
__attribute__((always_inline)) inline std::uint64_t spread_bits(std::uint64_t b) {
  const std::uint64_t x = (b * 0x0101010101010101ull) & 0x8040201008040201ull;  // byte i: bit i
  return (((x | (x + 0x7F7F7F7F7F7F7F7Full)) & 0x8080808080808080ull) >> 7) * 0xFF;
}

// Voxels [x0, nx) of write_cells_row() (x0 a multiple of 8), a cell (8 voxels, a byte of a word)
// per step.
__attribute__((always_inline)) inline void write_cells_row_from(const std::uint8_t* cs, const word_t* w, std::size_t x0,
                                                                std::size_t nx, std::uint8_t* st) {
  std::size_t cx = x0 / 8;
  for (; (cx + 1) * 8 <= nx; ++cx) {
    const std::uint64_t unknown = spread_bits((w[cx / 8] >> (8 * (cx % 8))) & 0xFF);
    const std::uint64_t v =
        ((0x0101010101010101ull * cs[cx]) & ~unknown) | (0x0101010101010101ull * kUnknown & unknown);
    std::memcpy(st + 8 * cx, &v, 8);
  }
  for (std::size_t x = 8 * cx; x < nx; ++x) st[x] = ((w[x / 64] >> (x % 64)) & 1u) ? kUnknown : cs[cx];
}

}  // namespace occseg::kernels::generic
