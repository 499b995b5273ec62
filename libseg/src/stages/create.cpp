// Stage 4 (section 3.2): segment creation, from the block means (eq. 3) summed cell by cell.
#include "stages/create.hpp"

#include <algorithm>
#include <cstring>
#include <optional>
#include <utility>

#include "kernels/kernels.hpp"
#include "occseg/parallel.hpp"
#include "stages/map_rows.hpp"
#include "stages/own_states.hpp"
#include "util/bit_rows.hpp"
#include "util/huge_pages.hpp"

namespace occseg {

using detail::word_t;

double mean_occupancy(const Grid& grid, const Block& b) {
  // Cell by cell (kMeanCell^3 cells anchored at voxel 0), each cell's part in scan order.
  constexpr std::uint32_t k = kMeanCell;
  detail::MapRows map(grid);
  double sum = 0;
  for (std::uint32_t cz = b.lo[2] / k * k; cz < b.hi[2]; cz += k)
    for (std::uint32_t cy = b.lo[1] / k * k; cy < b.hi[1]; cy += k)
      for (std::uint32_t cx = b.lo[0] / k * k; cx < b.hi[0]; cx += k) {
        double part = 0;
        for (std::uint32_t z = std::max(cz, b.lo[2]); z < std::min(cz + k, b.hi[2]); ++z)
          for (std::uint32_t y = std::max(cy, b.lo[1]); y < std::min(cy + k, b.hi[1]); ++y) {
            const std::uint32_t x0 = std::max(cx, b.lo[0]), x1 = std::min(cx + k, b.hi[0]);
            const float* run = map.run(grid.index(x0, y, z), x1 - x0);
            for (std::uint32_t x = x0; x < x1; ++x) part += run[x - x0];
          }
        sum += part;
      }
  return sum / static_cast<double>(b.volume());
}

detail::OwnBitsStore detail::pack_own_bits(const std::uint8_t* own, const Dims& d, int threads,
                                           const kernels::CreateKernels& k) {
  OwnBitsStore s;
  const std::size_t words = (d.nx + 63) / 64;
  s.unknown.resize(d.ny * d.nz * words);
  s.occupied.resize(d.ny * d.nz * words);
  pack_own_bits(own, d, threads, s.unknown.data(), s.occupied.data(), k);
  s.bits = OwnBits{s.unknown.data(), s.occupied.data(), words};
  return s;
}

void detail::pack_own_bits(const std::uint8_t* own, const Dims& d, int threads, std::uint64_t* unknown,
                           std::uint64_t* occupied, const kernels::CreateKernels& k) {
  const std::size_t words = (d.nx + 63) / 64;
  parallel_for(d.ny * d.nz, threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r) {
      const std::uint8_t* row = own + r * d.nx;
      constexpr auto kUnknownOwn = static_cast<std::uint8_t>(State::unknown);
      constexpr auto kOccupiedOwn = static_cast<std::uint8_t>(State::occupied);
      k.pack_equal(row, d.nx, kUnknownOwn, reinterpret_cast<word_t*>(unknown) + r * words);
      k.pack_equal(row, d.nx, kOccupiedOwn, reinterpret_cast<word_t*>(occupied) + r * words);
    }
  });
}

detail::CellRows::CellRows(const Grid& grid, std::uint8_t* own, float lo, float hi, std::uint64_t* unknown_bits,
                           std::uint64_t* occupied_bits, const kernels::CreateKernels& k)
    : grid_(&grid),
      own_(own),
      unknown_(unknown_bits),
      occupied_(occupied_bits),
      lo_(lo),
      hi_(hi),
      ncx_((grid.dims.nx + kMeanCell - 1) / kMeanCell),
      ncy_((grid.dims.ny + kMeanCell - 1) / kMeanCell),
      k_(&k),
      sum_(ncx_ * ncy_ * ((grid.dims.nz + kMeanCell - 1) / kMeanCell), 0.0) {}

void detail::CellRows::add_row(std::size_t y, std::size_t z, const float* row) {
  constexpr std::size_t c = kMeanCell;
  static_assert(kMeanCell == 8, "add_cells adds eight voxels per cell");
  const std::size_t nx = grid_->dims.nx, i0 = nx * (y + grid_->dims.ny * z);
  if (own_) {
    k_->own_states(row, nx, lo_, hi_, own_ + i0);
  } else if (unknown_ && occupied_) {  // the own states as bits only, straight from the values
    const std::size_t w = (nx + 63) / 64 * (y + grid_->dims.ny * z);
    k_->own_bits(row, nx, lo_, hi_, reinterpret_cast<word_t*>(unknown_) + w, reinterpret_cast<word_t*>(occupied_) + w);
  }
  double* const sums = sum_.data() + ncx_ * (y / c + ncy_ * (z / c));
  const std::size_t whole = nx / c;
  k_->add_cells(row, sums, whole);  // whole cells: eight additions each
  if (whole < ncx_) {               // the cell cut by the far face
    double acc = sums[whole];
    for (std::size_t x = whole * c; x < nx; ++x) acc += row[x];
    sums[whole] = acc;
  }
}

namespace {

constexpr auto kFreeState = static_cast<std::uint8_t>(State::free);
constexpr auto kUnknownState = static_cast<std::uint8_t>(State::unknown);
constexpr auto kOccupiedState = static_cast<std::uint8_t>(State::occupied);

// 0xFF in each byte of `eight` equal to v, 0 in the others (exact: no borrow between bytes).
inline std::uint64_t bytes_equal(std::uint64_t eight, std::uint8_t v) {
  constexpr std::uint64_t low7 = 0x7F7F7F7F7F7F7F7Full, high = 0x8080808080808080ull;
  const std::uint64_t x = eight ^ (0x0101010101010101ull * v);  // 0 where equal
  const std::uint64_t nonzero = ((x & low7) + low7) | x;         // bit 7 of a byte: byte != 0
  return ((~nonzero & high) >> 7) * 0xFF;
}

// Block by block: any set of disjoint blocks. Voxels outside every block are left free.
void create_by_blocks(const Grid& grid, const std::vector<Block>& blocks, const Params& params, std::uint8_t* own,
                      float lo, float hi, std::uint8_t* states, const kernels::CreateKernels& kern) {
  // Blocks in scan order of their corners: division lists them tree by tree, octant by octant,
  // and neighbours along x (whose 32-byte rows share cache lines) came far apart.
  std::vector<std::pair<std::uint64_t, std::size_t>> order(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) order[i] = {grid.index(blocks[i].lo[0], blocks[i].lo[1], blocks[i].lo[2]), i};
  std::sort(order.begin(), order.end());
  parallel_for_dynamic(blocks.size(), params.threads, [&](std::size_t b, std::size_t e) {
    detail::MapRows map(grid);
    for (std::size_t k = b; k < e; ++k) {  // blocks are disjoint: no two threads write one voxel
      const Block& blk = blocks[order[k].second];
      const std::size_t width = blk.hi[0] - blk.lo[0];
      if (own)  // the block's rows are about to be read for its mean: in cache for both
        for (std::uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
          for (std::uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y) {
            const std::size_t at = grid.index(blk.lo[0], y, z);
            kern.own_states(map.run(at, width), width, lo, hi, own + at);
          }
      const auto s = static_cast<std::uint8_t>(params.state_of(mean_occupancy(grid, blk)));
      for (std::uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
        for (std::uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y) std::memset(states + grid.index(blk.lo[0], y, z), s, width);
    }
  });
}

// Row by row, for blocks that tile the map on the lattice of kMeanCell^3 cells (division's leaves
// for Smin >= 8: cubes aligned to their size, clipped by the map's far faces). Each row adds
// its voxels to the running sums of the cells it crosses, in the row's order, so each cell's
// voxels arrive in scan order; the block sums add their cells' sums in scan order of the cells:
// mean_occupancy(), bit for bit. The map is read once, as a stream, and every row adds into
// nx / 8 independent sums (one chain of additions through a whole block, as a block-by-block
// sum in scan order needs, ran at the latency of an addition). Returns false (nothing written)
// for other blocks. With `means`, the blocks' means go there and no states are written.
bool create_by_rows(const Grid& grid, const std::vector<Block>& blocks, const Params& params, detail::CellRows& rows,
                    bool summed, std::uint8_t* states, std::vector<double>* means = nullptr,
                    detail::GrowthRows* growth = nullptr) {
  const Dims& d = grid.dims;
  const std::size_t dim[3] = {d.nx, d.ny, d.nz};
  constexpr std::size_t c = kMeanCell;
  for (const Block& b : blocks)
    for (int a = 0; a < 3; ++a) {
      if (b.hi[a] <= b.lo[a] || b.hi[a] > dim[a]) return false;
      if (b.lo[a] % c || (b.hi[a] != dim[a] && b.hi[a] % c)) return false;  // off the lattice
    }
  const std::size_t ncx = rows.cells_x(), ncy = rows.cells_y(), ncz = (d.nz + c - 1) / c;
  // fn(index of the cell) for the cells of block b, in scan order.
  const auto for_cells = [&](const Block& b, auto&& fn) {
    for (std::size_t z = b.lo[2] / c; z < (b.hi[2] + c - 1) / c; ++z)
      for (std::size_t y = b.lo[1] / c; y < (b.hi[1] + c - 1) / c; ++y)
        for (std::size_t x = b.lo[0] / c; x < (b.hi[0] + c - 1) / c; ++x) fn(x + ncx * (y + ncy * z));
  };
  // Which block each cell belongs to; every cell exactly once, or this is no tiling.
  std::vector<std::uint32_t> cell(ncx * ncy * ncz, ~0u);
  bool tiling = true;
  for (std::size_t k = 0; k < blocks.size() && tiling; ++k)
    for_cells(blocks[k], [&](std::size_t i) {
      tiling = tiling && cell[i] == ~0u;
      cell[i] = static_cast<std::uint32_t>(k);
    });
  if (!tiling) return false;
  for (std::uint32_t id : cell)
    if (id == ~0u) return false;

  // The cells' sums, a row of cells (c planes of c rows) per task, unless they are summed already.
  if (!summed)
    parallel_for_dynamic(ncy * ncz, params.threads, [&](std::size_t t0, std::size_t t1) {
      detail::MapRows map(grid);
      for (std::size_t t = t0; t < t1; ++t) {
        const std::size_t cy = t % ncy, cz = t / ncy;
        for (std::size_t z = cz * c; z < std::min(d.nz, cz * c + c); ++z)
          for (std::size_t y = cy * c; y < std::min(d.ny, cy * c + c); ++y) rows.add_row(y, z, map.row(y, z));
      }
    });
  const std::vector<double>& cell_sum = rows.sums();
  // Each block's sum over its cells in scan order, each cell's state, then the states row by row.
  std::vector<std::uint8_t> cell_state(cell.size());
  if (means) means->assign(blocks.size(), 0.0);
  parallel_for(blocks.size(), params.threads, [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k) {
      const Block& b = blocks[k];
      double sum = 0;
      for_cells(b, [&](std::size_t i) { sum += cell_sum[i]; });
      const double mean = sum / static_cast<double>(b.volume());
      if (means) (*means)[k] = mean;
      const auto st = static_cast<std::uint8_t>(params.state_of(mean));
      for_cells(b, [&](std::size_t i) { cell_state[i] = st; });
    }
  });
  if (means) return true;
  // The growth's masks (GrowthRows): a cell covers 8 voxels of a row, a byte of a mask word, so
  // word i of a row holds cells 8i .. 8i + 7 (static_assert below), each byte 0xFF or 0.
  static_assert(kMeanCell == 8, "a cell must be one byte of the growth's mask words");
  const std::size_t words = (d.nx + 63) / 64;
  const bool defer = growth && growth->defer_states;  // the growth writes the states
  detail::word_t* const W = growth ? reinterpret_cast<detail::word_t*>(growth->scratch) : nullptr;
  detail::word_t* const C = W ? W + d.ny * d.nz * words : nullptr;
  const std::uint64_t last = d.nx % 64 ? (std::uint64_t(1) << (d.nx % 64)) - 1 : ~std::uint64_t(0);
  parallel_for(d.ny * d.nz, params.threads, [&](std::size_t r0, std::size_t r1) {
    // The masks of the row of cells the last row was in (the c rows of a row of cells share them).
    std::vector<std::uint64_t> cells_w(W ? words : 0), cells_c(W ? words : 0);
    std::size_t cells_row = ~std::size_t(0);
    bool cells_occupied = false;
    for (std::size_t r = r0; r < r1; ++r) {
      const std::size_t cr = r % d.ny / c + ncy * (r / d.ny / c);
      const std::uint8_t* cs = cell_state.data() + ncx * cr;
      if (!defer) {
        std::uint8_t* row = states + d.nx * r;
        std::size_t cx = 0;
        for (; (cx + 1) * c <= d.nx; ++cx) {  // one 8-byte store per cell
          const std::uint64_t eight = 0x0101010101010101ull * cs[cx];
          std::memcpy(row + cx * c, &eight, c);
        }
        if (cx < ncx) std::memset(row + cx * c, cs[cx], d.nx - cx * c);
      }
      if (!W) continue;
      if (cr != cells_row) {
        cells_row = cr;
        for (std::size_t i = 0; i < words; ++i) {
          std::uint64_t eight = ~std::uint64_t(0);  // past the last cell: no state
          std::memcpy(&eight, cs + 8 * i, std::min<std::size_t>(8, ncx - 8 * i));
          const std::uint64_t keep = i + 1 == words ? last : ~std::uint64_t(0);
          cells_w[i] = bytes_equal(eight, kUnknownState) & keep;
          cells_c[i] = bytes_equal(eight, kFreeState) & keep;
        }
        cells_occupied = std::memchr(cs, kOccupiedState, ncx) != nullptr;
      }
      for (std::size_t i = 0; i < words; ++i) {
        W[r * words + i] = cells_w[i];
        C[r * words + i] = cells_c[i] & growth->unknown_bits[r * words + i];
      }
      growth->occupied_rows[r] = cells_occupied;
    }
  });
  if (growth) growth->filled = true;
  if (defer) growth->cell_states = std::move(cell_state);
  return true;
}

// V: std::vector (zeroed first) for the public create_segments(), UninitVector for the pipeline,
// whose states are all written here, in parallel.
template <class V>
V create(const Grid& grid, const std::vector<Block>& blocks, const Params& params, std::uint8_t* own,
         detail::CellRows* summed, detail::GrowthRows* growth, const kernels::Table& k) {
  V states;
  resize_huge(states, grid.dims.count());
  float lo = 0, hi = 0;
  if (own) detail::float_bounds(params.free_below, params.occupied_above, lo, hi);
  std::optional<detail::CellRows> fresh;  // the rows are summed here unless they were (not copied)
  detail::CellRows& rows = summed ? *summed : fresh.emplace(grid, own, lo, hi, nullptr, nullptr, k.create);
  if (!create_by_rows(grid, blocks, params, rows, summed != nullptr, states.data(), nullptr, growth))
    create_by_blocks(grid, blocks, params, own, lo, hi, states.data(), k.create);
  return states;
}

}  // namespace

std::vector<double> detail::block_means_by_rows(const Grid& grid, const std::vector<Block>& blocks, int threads) {
  Params p;
  p.threads = threads;
  std::vector<double> means;
  detail::CellRows rows(grid, nullptr, 0, 0);
  create_by_rows(grid, blocks, p, rows, false, nullptr, &means);
  return means;
}

std::vector<std::uint8_t> create_segments(const Grid& grid, const std::vector<Block>& blocks, const Params& params,
                                          const kernels::Table& k) {
  return create<std::vector<std::uint8_t>>(grid, blocks, params, nullptr, nullptr, nullptr, k);
}

UninitVector<std::uint8_t> detail::create_segments_and_own_states(const Grid& grid, const std::vector<Block>& blocks,
                                                                  const Params& params, std::uint8_t* own,
                                                                  CellRows* summed, GrowthRows* growth,
                                                                  const kernels::Table& k) {
  return create<UninitVector<std::uint8_t>>(grid, blocks, params, own, summed, growth, k);
}

}  // namespace occseg
