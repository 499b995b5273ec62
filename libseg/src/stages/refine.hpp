// Stage 5 (section 3.3): refinement scans along the six axis directions over the voxel states.
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"

namespace occseg {

// One scan direction: axis 0/1/2 (x/y/z), forward (+1) or backward (-1).
struct ScanDirection {
  int axis;
  int step;
};
extern const ScanDirection kSixDirections[6];

// Step 1: along each direction, a free voxel right after an unknown one whose probability is at
// 0.5 becomes unknown; this continues until a voxel with another value is met.
void refine_unknown(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params);

// Step 2: `params.refine_passes` passes of the six scans. At each free->occupied
// (occupied->free) boundary the next `lookahead` voxels of the segment entered are examined and
// reassigned by the paper's four cases.
void refine_boundaries(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params);

// The state each voxel's own probability gives (values of occseg::State: params.state_of(p)).
// Refinement and the default rules only ever look at probabilities through it.
std::vector<std::uint8_t> own_states(const Grid& grid, const Params& params);

// The same two steps with the own states already computed (own_states(grid, params)); the
// pipeline computes them once for all stages.
void refine_unknown(std::vector<std::uint8_t>& states, const std::vector<std::uint8_t>& own, const Dims& dims,
                    const Params& params);
void refine_boundaries(std::vector<std::uint8_t>& states, const std::vector<std::uint8_t>& own, const Dims& dims,
                       const Params& params);

// The four cases for one window of probabilities beyond a boundary: `into` is the state of the
// segment entered (free or occupied), `from` the state before the boundary. Sets reassign[k]
// for each voxel that moves to `from`. Exposed for unit tests.
void classify_window(const float* p, int n, std::uint8_t from, std::uint8_t into,
                     const Params& params, bool* reassign);

}  // namespace occseg
