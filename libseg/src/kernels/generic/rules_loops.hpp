// The default rules' plain row loop (kernels/rules.hpp), shared by the levels: scalar/ compiles it
// as it is, avx2/ for its short rows. always_inline, so that it is compiled for the target of the
// level's function that calls it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/rules.hpp"
#include "rules/voxel_rules.hpp"

namespace occseg::kernels::generic {

// voxel_rule() and gap_seed() on each voxel of the row, in x order; the result's bit rows when
// asked (`f`).
__attribute__((always_inline)) inline void rules_row(std::uint8_t* st, const word_t* u, const word_t* o,
                                                     const word_t* reg, const word_t* t, std::size_t n,
                                                     std::size_t first, std::vector<std::size_t>& seeds, word_t* f,
                                                     word_t* un, word_t* oc) {
  if (f)
    for (std::size_t i = 0; i < (n + 63) / 64; ++i) f[i] = un[i] = oc[i] = 0;
  for (std::size_t x = 0; x < n; ++x) {
    const std::size_t i = x / 64;
    const unsigned b = x % 64;
    const bool unknown = (u[i] >> b) & 1u, region = (reg[i] >> b) & 1u, touches = (t[i] >> b) & 1u;
    const std::uint8_t own = unknown ? rules::kUnknown : (((o[i] >> b) & 1u) ? rules::kOccupied : rules::kFree);
    st[x] = rules::voxel_rule(st[x], own, region, touches);
    if (rules::gap_seed(own, region, touches, st[x])) seeds.push_back(first + x);
    if (f) {
      word_t* const to = st[x] == rules::kFree ? f : (st[x] == rules::kUnknown ? un : oc);
      to[i] |= std::uint64_t(1) << b;
    }
  }
}

}  // namespace occseg::kernels::generic
