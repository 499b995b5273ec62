// Stage 3 (section 3.1): hierarchical division of the map into blocks of uniform texture.
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"
#include "stages/texture.hpp"

namespace occseg {

// The split decision of eq. (2) over the G-statistics of all pairs of sibling histograms:
// split when Gmax / Gmin > X. Gmin = 0 with Gmax > 0 is an infinite ratio (split); all G = 0 means
// identical textures (no split). Fewer than two histograms give no evidence (no split).
bool should_split(const std::vector<const std::uint32_t*>& histograms, std::size_t bins, double x);

// Tiles the map with Smax blocks anchored at voxel (0,0,0), clipped by the map's far faces, and
// splits each recursively into octants down to Smin. Leaves come out in a fixed order
// (top blocks in x-fastest order, octants depth-first), whatever the thread count.
std::vector<Block> divide(const Grid& grid, const TextureMap& texture, const Params& params);

// Histogram of the texture codes of block b (h: `bins` counts, overwritten); kNoTexture voxels
// are not counted. The division's own counting, exposed for unit tests.
void count_codes(const TextureMap& texture, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h);

}  // namespace occseg
