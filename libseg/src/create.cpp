#include "occseg/create.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

#include "occseg/parallel.hpp"
#include "huge_pages.hpp"
#include "own_states_internal.hpp"

namespace occseg {

double mean_occupancy(const Grid& grid, const Block& b) {
  double sum = 0;
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
    for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y) {
      const float* row = grid.p.data() + grid.index(0, y, z);
      for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x) sum += row[x];
    }
  return sum / static_cast<double>(b.volume());
}

namespace {

std::vector<std::uint8_t> create(const Grid& grid, const std::vector<Block>& blocks, const Params& params,
                                 std::uint8_t* own) {
  std::vector<std::uint8_t> states;
  resize_huge(states, grid.dims.count());
  float lo = 0, hi = 0;
  if (own) detail::float_bounds(params.free_below, params.occupied_above, lo, hi);
  // Blocks in scan order of their corners: division lists them tree by tree, octant by octant,
  // and neighbours along x (whose 32-byte rows share cache lines) came far apart.
  std::vector<std::pair<std::uint64_t, std::size_t>> order(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) order[i] = {grid.index(blocks[i].lo[0], blocks[i].lo[1], blocks[i].lo[2]), i};
  std::sort(order.begin(), order.end());
  parallel_for_dynamic(blocks.size(), params.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {  // blocks are disjoint: no two threads write one voxel
      const Block& blk = blocks[order[k].second];
      const std::size_t width = blk.hi[0] - blk.lo[0];
      if (own)  // the block's rows are about to be read for its mean: in cache for both
        for (std::uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
          for (std::uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y) {
            const std::size_t at = grid.index(blk.lo[0], y, z);
            detail::own_states_of(grid.p.data() + at, width, lo, hi, own + at);
          }
      const auto s = static_cast<std::uint8_t>(params.state_of(mean_occupancy(grid, blk)));
      const std::uint64_t eight = 0x0101010101010101ull * s;
      for (std::uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
        for (std::uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y) {
          std::uint8_t* row = states.data() + grid.index(blk.lo[0], y, z);
          // Most leaves are Smin = 8 voxels wide: one 8-byte store per row instead of a loop.
          if (width == 8) std::memcpy(row, &eight, 8);
          else std::memset(row, s, width);
        }
    }
  });
  return states;
}

}  // namespace

std::vector<std::uint8_t> create_segments(const Grid& grid, const std::vector<Block>& blocks,
                                          const Params& params) {
  return create(grid, blocks, params, nullptr);
}

std::vector<std::uint8_t> detail::create_segments_and_own_states(const Grid& grid, const std::vector<Block>& blocks,
                                                                 const Params& params, std::uint8_t* own) {
  return create(grid, blocks, params, own);
}

}  // namespace occseg
