// Stage 5 (section 3.3): refinement scans along the six axis directions over the voxel states.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "stages/own_states.hpp"

namespace occseg {

// One scan direction: axis 0/1/2 (x/y/z), forward (+1) or backward (-1).
struct ScanDirection {
  int axis;
  int step;
};
extern const ScanDirection kSixDirections[6];

// Step 1: along each direction, a free voxel right after an unknown one whose probability is at
// 0.5 becomes unknown; this continues until a voxel with another value is met.
void refine_unknown(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params,
                    const kernels::Table& k = kernels::active());

// Step 2: `params.refine_passes` passes of the six scans. At each free->occupied
// (occupied->free) boundary the next `lookahead` voxels of the segment entered are examined and
// reassigned by the paper's four cases.
void refine_boundaries(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params,
                       const kernels::Table& k = kernels::active());

// The state each voxel's own probability gives (values of occseg::State: params.state_of(p)).
// Refinement and the default rules only ever look at probabilities through it.
std::vector<std::uint8_t> own_states(const Grid& grid, const Params& params);

// The same two steps with the own states already computed (own_states(grid, params)).
void refine_unknown(std::vector<std::uint8_t>& states, const std::vector<std::uint8_t>& own, const Dims& dims,
                    const Params& params, const kernels::Table& k = kernels::active());
void refine_boundaries(std::vector<std::uint8_t>& states, const std::vector<std::uint8_t>& own, const Dims& dims,
                       const Params& params, const kernels::Table& k = kernels::active());

// The four cases for one window of probabilities beyond a boundary: `into` is the state of the
// segment entered (free or occupied), `from` the state before the boundary. Sets reassign[k]
// for each voxel that moves to `from`. The scans decide by the same function on the windows' own
// states (params.state_of(p)).
void classify_window(const float* p, int n, std::uint8_t from, std::uint8_t into,
                     const Params& params, bool* reassign);

namespace detail {

// Step 1 on bit masks (refine_unknown.cpp), kept in `scratch` (8-byte aligned) when it has
// grow_unknown_scratch_bytes(), else in an array of its own. With `unknown_bits` (CellRows' bits
// of `own`), own is not read.
std::size_t grow_unknown_scratch_bytes(const Dims& dims);
// With `occupied_rows` (one byte per row of voxels), row r's byte says whether it holds an
// occupied voxel.
// With `packed` (GrowthRows filled by the creation), scratch and occupied_rows hold every row's
// masks and flag already: the states are not read before the scans.
// With `cell_states` (GrowthRows' deferred states; `packed` too), the states are not read or
// written before: every row is written at the end from its cells' states and the grown voxels.
void grow_unknown(std::uint8_t* states, const std::uint8_t* own, const Dims& dims, int threads,
                  std::uint8_t* scratch, std::size_t scratch_bytes, const std::uint64_t* unknown_bits = nullptr,
                  std::uint8_t* occupied_rows = nullptr, bool packed = false,
                  const std::uint8_t* cell_states = nullptr, const kernels::Table& k = kernels::active());

// Step 1 then step 2 with the own states as bits, the masks of the first in `scratch` if it has
// room; `growth` (its scratch the same as `scratch`), when the creation filled it.
void refine(std::uint8_t* states, const OwnBits& own, const Dims& dims, const Params& params, std::uint8_t* scratch,
            std::size_t scratch_bytes, const GrowthRows* growth, const kernels::Table& k);

}  // namespace detail

}  // namespace occseg
