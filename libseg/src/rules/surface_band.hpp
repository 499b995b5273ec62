// The surface band (docs/algorithm.md, default preset rule 10): the free-valued voxels of the
// noisy band just inside an occupied surface go to the object. Applied to the per-voxel states
// after rules 1-3 (rules/departures.hpp) and before the labelling.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "rules/state_bits.hpp"

namespace occseg {

// With r = params.surface_band (0: nothing changes), a voxel whose state is free becomes occupied
// when all three hold:
//  - it is *thin* free space: no 3 x 3 x 3 cube made only of free voxels holds it (a cube centred
//    in the map, whose voxels outside the map count as free, so free space cut by the map's faces
//    stays thick). The free space in front of
//    a surface, crossed by many rays, is thick; the band the rays' overshoot leaves inside an
//    object is not, and neither is a free region of a noise-free map at least 3 voxels thick in
//    every direction (such maps stay voxel-exact);
//  - an occupied voxel lies within r face steps (6-connected) of it: the surface;
//  - an unknown voxel lies within r face steps of it: the never-observed inside the surface
//    encloses (or a gap rule 3 made unknown).
// Every test reads the states as they were before the rule (no cascade: a converted voxel never
// makes another one thin). Only free voxels change, and only to occupied: a voxel whose own
// probability is occupied is never made free, an unknown voxel never changes. Rows are
// independent: the result never depends on `params.threads`. `scratch` (8-byte aligned, or
// nullptr) holds the rule's seven bit masks if it has room (scratch_bytes). `added` (if given)
// receives the voxels made occupied as a bit mask (ceil(nx / 64) words per row of voxels).
void apply_surface_band(std::uint8_t* states, const Dims& dims, const Params& params, std::uint8_t* scratch = nullptr,
                        std::size_t scratch_bytes = 0, std::vector<std::uint64_t>* added = nullptr,
                        const kernels::Table& k = kernels::active());
inline void apply_surface_band(std::vector<std::uint8_t>& states, const Dims& dims, const Params& params) {
  apply_surface_band(states.data(), dims, params);
}

// Per segment id: how many of its voxels the rule added (`added` as apply_surface_band gives it,
// the labels after the labelling; empty `added`: all 0). Rule 7 leaves them out of a group's size
// (rules/objects.hpp).
std::vector<std::uint64_t> surface_band_voxels(const std::vector<std::uint64_t>& added, const Dims& dims,
                                               const std::uint32_t* labels, std::size_t segments);

// The bytes of scratch the rule uses on a map of `dims` (seven bit masks).
std::size_t surface_band_scratch_bytes(const Dims& dims);

namespace detail {

// StateBits of `states`, its masks in `storage` (3 * ny * nz * words words), its row kinds in
// `rows` (ny * nz bytes).
void state_bits(const std::uint8_t* states, const Dims& dims, int threads, std::uint64_t* storage, std::uint8_t* rows,
                StateBits& out, const kernels::Table& k = kernels::active());

// apply_surface_band() with the states' bits already made (they must be those of `states`, and
// are not updated); `scratch` (8-byte aligned, or nullptr) holds its four masks if it has room
// (surface_band_rows_scratch_bytes).
void apply_surface_band(std::uint8_t* states, const StateBits& bits, const Dims& dims, const Params& params,
                        std::uint8_t* scratch, std::size_t scratch_bytes, std::vector<std::uint64_t>* added);
std::size_t surface_band_rows_scratch_bytes(const Dims& dims);

}  // namespace detail

}  // namespace occseg
