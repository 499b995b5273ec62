// Stage 4 (section 3.2): segment creation. Every leaf block gets the state of its mean occupancy
// probability (eq. 3); adjacent blocks of one state form one segment.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "stages/divide.hpp"

namespace occseg {

// Edge of the cells a block mean is summed by: the block's voxels are added cell by cell over the
// lattice of kMeanCell^3 cells anchored at voxel (0, 0, 0), each cell's part in scan order (x
// fastest), the parts in scan order of the cells. A fixed order, so a mean never depends on the
// thread count; by cells, so that creation reads the map once, row by row, into many
// independent sums (docs/algorithm.md).
constexpr std::uint32_t kMeanCell = 8;

// The mean occupancy probability of `block` (eq. 3), summed in the order above.
double mean_occupancy(const Grid& grid, const Block& block);

// Paints each block's MOP state into a per-voxel state array (values of occseg::State). The
// merging of adjacent same-state blocks is the connected-component labelling of this array
// (stages/label.hpp), done once at the end so refinement can move voxels between segments freely.
std::vector<std::uint8_t> create_segments(const Grid& grid, const std::vector<Block>& blocks, const Params& params,
                                          const kernels::Table& k = kernels::active());

}  // namespace occseg
