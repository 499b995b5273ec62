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

// Block by block: any set of disjoint blocks. Voxels outside every block are left free.
void create_by_blocks(const Grid& grid, const std::vector<Block>& blocks, const Params& params, std::uint8_t* own,
                      float lo, float hi, std::uint8_t* states) {
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
      for (std::uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
        for (std::uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y) std::memset(states + grid.index(blk.lo[0], y, z), s, width);
    }
  });
}

// Row by row, for blocks that tile the map on a lattice of cells (division's leaves: cubes of
// Smin << k voxels aligned to their size, clipped by the map's far faces). Reading the map in
// scan order streams it; block by block, 64 rows of 32 bytes per Smin block, the reading waited
// on memory and each block's sum was one chain of dependent additions. A row adds its voxels to
// the running sum of the block each stretch belongs to, in the row's order: a block's voxels
// arrive in the same order as in mean_occupancy() (z, then y, then x), so every sum, and every
// state, is the same bit for bit. Returns false (nothing written) for other blocks.
bool create_by_rows(const Grid& grid, const std::vector<Block>& blocks, const Params& params, std::uint8_t* own,
                    float lo, float hi, std::uint8_t* states) {
  const Dims& d = grid.dims;
  const std::size_t dim[3] = {d.nx, d.ny, d.nz};
  // The cell: the largest power of two (up to 64) that every block's corners sit on, the far
  // faces of the map excepted. Cells below 4 voxels would cost too much memory: not this path.
  std::uint32_t bits = 64, extent = 1;
  for (const Block& b : blocks)
    for (int a = 0; a < 3; ++a) {
      if (b.hi[a] <= b.lo[a] || b.hi[a] > dim[a]) return false;
      bits |= b.lo[a] | (b.hi[a] == dim[a] ? 0u : b.hi[a]);
      if (a > 0) extent = std::max(extent, b.hi[a] - b.lo[a]);
    }
  const std::size_t c = bits & (~bits + 1);  // lowest set bit
  if (c < 4) return false;
  const std::size_t ncx = (d.nx + c - 1) / c, ncy = (d.ny + c - 1) / c, ncz = (d.nz + c - 1) / c;
  // Which block each cell belongs to; every cell exactly once, or this is no tiling.
  std::vector<std::uint32_t> cell(ncx * ncy * ncz, ~0u);
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const Block& b = blocks[k];
    for (std::size_t z = b.lo[2] / c; z < (b.hi[2] + c - 1) / c; ++z)
      for (std::size_t y = b.lo[1] / c; y < (b.hi[1] + c - 1) / c; ++y)
        for (std::size_t x = b.lo[0] / c; x < (b.hi[0] + c - 1) / c; ++x) {
          std::uint32_t& id = cell[x + ncx * (y + ncy * z)];
          if (id != ~0u) return false;
          id = static_cast<std::uint32_t>(k);
        }
  }
  for (std::uint32_t id : cell)
    if (id == ~0u) return false;
  // Bands of `band` rows in y and planes in z that no block crosses (division's blocks stay in
  // their Smax tree) are independent: one task each; else the whole map is one task.
  std::size_t band = 1;
  while (band < extent) band *= 2;
  for (const Block& b : blocks)
    for (int a = 1; a < 3; ++a)
      if (b.lo[a] / band != (b.hi[a] - 1) / band) band = std::max(d.ny, d.nz);
  const std::size_t nby = (d.ny + band - 1) / band, nbz = (d.nz + band - 1) / band;

  std::vector<double> sum(blocks.size(), 0.0);
  const float* p = grid.p.data();
  parallel_for_dynamic(nby * nbz, params.threads, [&](std::size_t t0, std::size_t t1) {
    for (std::size_t t = t0; t < t1; ++t) {
      const std::size_t y0 = (t % nby) * band, z0 = (t / nby) * band;
      for (std::size_t z = z0; z < std::min(d.nz, z0 + band); ++z)
        for (std::size_t y = y0; y < std::min(d.ny, y0 + band); ++y) {
          const std::size_t i0 = d.nx * (y + d.ny * z);
          if (own) detail::own_states_of(p + i0, d.nx, lo, hi, own + i0);
          const std::uint32_t* row_cells = cell.data() + ncx * (y / c + ncy * (z / c));
          for (std::size_t cx = 0; cx < ncx;) {
            // the block's stretch of this row: its consecutive cells
            const std::uint32_t id = row_cells[cx];
            std::size_t ce = cx + 1;
            while (ce < ncx && row_cells[ce] == id) ++ce;
            const std::size_t xe = std::min(d.nx, ce * c);
            double acc = sum[id];
            for (std::size_t x = cx * c; x < xe; ++x) acc += p[i0 + x];
            sum[id] = acc;
            cx = ce;
          }
        }
    }
  });
  // Each cell's state, then the states row by row.
  std::vector<std::uint8_t> cell_state(cell.size());
  for (std::size_t k = 0; k < cell.size(); ++k) {
    const std::uint32_t id = cell[k];
    cell_state[k] = static_cast<std::uint8_t>(params.state_of(sum[id] / static_cast<double>(blocks[id].volume())));
  }
  parallel_for(d.ny * d.nz, params.threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r) {
      const std::uint8_t* cs = cell_state.data() + ncx * (r % d.ny / c + ncy * (r / d.ny / c));
      std::uint8_t* row = states + d.nx * r;
      std::size_t cx = 0;
      if (c == 8)  // Smin = 8, the default: one 8-byte store per cell
        for (; (cx + 1) * 8 <= d.nx; ++cx) {
          const std::uint64_t eight = 0x0101010101010101ull * cs[cx];
          std::memcpy(row + cx * 8, &eight, 8);
        }
      for (; cx < ncx; ++cx) std::memset(row + cx * c, cs[cx], std::min(c, d.nx - cx * c));
    }
  });
  return true;
}

std::vector<std::uint8_t> create(const Grid& grid, const std::vector<Block>& blocks, const Params& params,
                                 std::uint8_t* own) {
  std::vector<std::uint8_t> states;
  resize_huge(states, grid.dims.count());
  float lo = 0, hi = 0;
  if (own) detail::float_bounds(params.free_below, params.occupied_above, lo, hi);
  if (!create_by_rows(grid, blocks, params, own, lo, hi, states.data()))
    create_by_blocks(grid, blocks, params, own, lo, hi, states.data());
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
