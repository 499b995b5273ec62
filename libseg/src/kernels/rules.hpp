// The default rules' kernels (rules/departures.cpp): the slots, each level's versions, and how a
// table fills them. Bit rows are util/bit_rows.hpp's (64 voxels per word_t, voxel x at bit x % 64
// of word x / 64); voxel states are bytes (occseg::State's values).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/isa.hpp"
#include "util/bit_rows.hpp"

namespace occseg::kernels {

using detail::word_t;

struct RulesKernels {
  // rules/voxel_rules.hpp's voxel_rule() on the n voxels of a row, states st[0, n) in place, from
  // bit rows: u and o the own states (unknown: in the band; occupied: above it; bits past n 0),
  // reg the unknown regions (bits past n 0), t the voxels touching an occupied one (bits past n
  // any). Appends the gap flood's seeds (gap_seed()) to `seeds` as first + x, in x order. With `f`
  // (then `un` and `oc` too), also writes the resulting states as bit rows (ceil(n / 64) words
  // each, bits past n 0): f free, un unknown, oc occupied.
  void (*rules_row)(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg, const word_t* t,
                    std::size_t n, std::size_t first, std::vector<std::size_t>& seeds, word_t* f, word_t* un,
                    word_t* oc) = nullptr;
  // out[x] = 1 where bit x of `bits` is set and own[x] is unknown, else 0, for x < nx.
  void (*unpack_half)(const word_t* bits, const std::uint8_t* own, std::size_t nx, std::uint8_t* out) = nullptr;
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_rules(RulesKernels& k, Isa cap);

// Each level's kernels (for select_rules(); a level without its own version of a slot uses the one
// below it). scalar/: plain C++, the meaning of every slot.
namespace scalar {
void rules_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg, const word_t* t, std::size_t n,
               std::size_t first, std::vector<std::size_t>& seeds, word_t* f, word_t* un, word_t* oc);
void unpack_half(const word_t* bits, const std::uint8_t* own, std::size_t nx, std::uint8_t* out);
}  // namespace scalar
namespace sse2 {
void unpack_half(const word_t* bits, const std::uint8_t* own, std::size_t nx, std::uint8_t* out);
}  // namespace sse2
namespace avx2 {
void rules_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg, const word_t* t, std::size_t n,
               std::size_t first, std::vector<std::size_t>& seeds, word_t* f, word_t* un, word_t* oc);
}  // namespace avx2
namespace avx512 {
void rules_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg, const word_t* t, std::size_t n,
               std::size_t first, std::vector<std::size_t>& seeds, word_t* f, word_t* un, word_t* oc);
}  // namespace avx512

}  // namespace occseg::kernels
