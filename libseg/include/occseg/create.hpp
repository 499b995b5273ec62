// Stage 4 (section 3.2): segment creation. Every leaf block gets the state of its mean occupancy
// probability (eq. 3); adjacent blocks of one state form one segment.
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/divide.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"

namespace occseg {

double mean_occupancy(const Grid& grid, const Block& block);

// Paints each block's MOP state into a per-voxel state array (values of occseg::State). The
// merging of adjacent same-state blocks is the connected-component labelling of this array
// (components.hpp), done once at the end so refinement can move voxels between segments freely.
std::vector<std::uint8_t> create_segments(const Grid& grid, const std::vector<Block>& blocks,
                                          const Params& params);

}  // namespace occseg
