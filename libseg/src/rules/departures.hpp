// The `default` preset's departures from the paper (docs/algorithm.md, "Two presets"):
// per-voxel rules applied after refinement so that what a voxel's own probability says clearly
// is never overruled by the block it sits in.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "rules/state_bits.hpp"
#include "stages/own_states.hpp"

namespace occseg {

// Marks the voxels at 0.5 that belong to an unknown *region*: the union of all (2r+1)^3 cubes
// made only of voxels at 0.5 (a morphological opening). The rest of the 0.5 voxels are gaps
// between sensor rays. Outside the map counts as 0.5, so regions cut by the map edge survive.
std::vector<std::uint8_t> unknown_regions(const Grid& grid, const Params& params,
                                          const kernels::Table& k = kernels::active());

// Final state of each voxel under the default preset:
//  - own state free or occupied: that state (an occupied voxel is never free; a voxel seen free
//    is free);
//  - at 0.5 inside an unknown region: unknown;
//  - at 0.5 in a gap: the state the texture segmentation gave it, except that a gap voxel that
//    touches an occupied voxel, and every free gap voxel connected to it through gap voxels,
//    becomes unknown (a hole in an object's shell, or the unobserved inside of a thin structure,
//    is not a way through).
// (The per-voxel statement of the three: rules/voxel_rules.hpp.)
void apply_voxel_rules(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params,
                       const kernels::Table& k = kernels::active());

// The same two with the voxels' own states (own_states() of refine.hpp) already computed.
std::vector<std::uint8_t> unknown_regions(const std::vector<std::uint8_t>& own, const Dims& dims, const Params& params,
                                          const kernels::Table& k = kernels::active());
void apply_voxel_rules(std::vector<std::uint8_t>& states, const std::vector<std::uint8_t>& own, const Dims& dims,
                       const Params& params, const kernels::Table& k = kernels::active());

namespace detail {
// apply_voxel_rules() with the own states as bits; `scratch` (8-byte aligned, or nullptr) holds
// the regions' bit mask if it has room. With `bits`, also the resulting states as StateBits, made
// on the way (the rules write every voxel's state): their masks in `bit_storage` (3 * ny * nz *
// ceil(nx / 64) words, apart from scratch), their row kinds in `row_kinds` (ny * nz bytes).
void apply_voxel_rules(std::uint8_t* states, const OwnBits& own, const Dims& dims, const Params& params,
                       std::uint8_t* scratch, std::size_t scratch_bytes, const kernels::Table& k,
                       StateBits* bits = nullptr, std::uint64_t* bit_storage = nullptr,
                       std::uint8_t* row_kinds = nullptr);
}  // namespace detail

}  // namespace occseg
