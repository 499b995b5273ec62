// Each voxel's own state (free below the band, occupied above it, unknown inside it), shared by
// own_states() (refine.cpp) and the segment creation that computes it on its way (create.cpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/uninit_vector.hpp"
#include "stages/divide.hpp"
#include "util/bit_rows.hpp"

namespace occseg::detail {

// Float thresholds equivalent to the double ones: for every float p,
// double(p) < below  <=>  p < lo   and   double(p) > above  <=>  p > hi.
void float_bounds(double below, double above, float& lo, float& hi);

// The own state of a value p: 0 (free) when p < lo, 2 (occupied) when p > hi, else 1 (also for
// NaN, which never reaches here: maps are checked first). With float_bounds() of the band, the
// state Params::state_of gives the value. The kernels' own_states and own_bits are tested
// against it.
inline std::uint8_t own_state_of(float p, float lo, float hi) {
  return static_cast<std::uint8_t>(p < lo ? 0 : (p > hi ? 2 : 1));
}

// out[i] = own_state_of(p[i]) for i in [0, n) (the kernels' own_states: CreateKernels).
inline void own_states_of(const float* p, std::size_t n, float lo, float hi, std::uint8_t* out) {
  for (std::size_t i = 0; i < n; ++i) out[i] = own_state_of(p[i], lo, hi);
}

// The voxels' own states as two bit masks in util/bit_rows.hpp's layout (row r of the map in
// words [r * words, (r + 1) * words), voxel x at bit x % 64 of word x / 64, bits past nx 0):
// `unknown` (p in the band) and `occupied` (above it); a free voxel has neither. The refinement
// and the default rules read these instead of a byte per voxel: segment()'s fused map pass
// (pipeline/map_pass.hpp) writes them from the map (CellRows), so no own state is ever written as
// a byte there.
struct OwnBits {
  const word_t* unknown = nullptr;  // (word_t: the words may live in the label array)
  const word_t* occupied = nullptr;
  std::size_t words = 0;  // per row: ceil(nx / 64)
  // The own state (State's value: 0 free, 1 unknown, 2 occupied) of voxel x of row r.
  std::uint8_t at(std::size_t r, std::size_t x) const {
    const std::size_t i = r * words + x / 64;
    const unsigned b = x % 64;
    return static_cast<std::uint8_t>(((unknown[i] >> b) & 1u) | (((occupied[i] >> b) & 1u) << 1));
  }
};

// OwnBits packed from own states in bytes (own_states()), with their storage (the public stages
// take the bytes).
struct OwnBitsStore {
  std::vector<std::uint64_t> unknown, occupied;
  OwnBits bits;
};
OwnBitsStore pack_own_bits(const std::uint8_t* own, const Dims& dims, int threads,
                           const kernels::CreateKernels& k = kernels::active().create);
// The same into caller storage (dims.ny * dims.nz * ceil(nx / 64) words each).
void pack_own_bits(const std::uint8_t* own, const Dims& dims, int threads, std::uint64_t* unknown,
                   std::uint64_t* occupied, const kernels::CreateKernels& k = kernels::active().create);

// Creation's reading of the map, row by row: each voxel's own state (into `own` as bytes, when
// given, else into `unknown_bits` and `occupied_bits` as OwnBits: the refinement's growth,
// boundary scans and rules start from those) and the sum of each kMeanCell^3 cell of the lattice
// anchored at voxel 0 (the far faces cut the last ones), its rows added in scan order, each row's
// voxels in x order: the order of mean_occupancy(). segment()'s fused map pass
// (pipeline/map_pass.hpp) adds each row right after the texture's first pass read it, while it
// is in the cache: creation then reads only these sums, not the map. The rows of one cell must be
// added by one thread, in scan order. The map itself is not read here: add_row() is handed each
// row's values. add_row() uses the kernels `k`, which must outlive the
// object (a table's do: kernels::table()), on whichever thread adds the row.
class CellRows {
 public:
  CellRows(const Grid& grid, std::uint8_t* own, float lo, float hi, std::uint64_t* unknown_bits = nullptr,
           std::uint64_t* occupied_bits = nullptr, const kernels::CreateKernels& k = kernels::active().create);
  // Row (y, z), whose nx values are `row` (MapRows gives them for a grid read through a source).
  void add_row(std::size_t y, std::size_t z, const float* row);
  const std::vector<double>& sums() const { return sum_; }  // cell (x, y, z) at x + ncx * (y + ncy * z)
  std::size_t cells_x() const { return ncx_; }
  std::size_t cells_y() const { return ncy_; }

 private:
  const Grid* grid_;
  std::uint8_t* own_;
  std::uint64_t* unknown_;
  std::uint64_t* occupied_;
  float lo_, hi_;
  std::size_t ncx_, ncy_;
  const kernels::CreateKernels* k_;
  std::vector<double> sum_;
};

// create_segments(), also writing every voxel's own state into `own` (grid.dims.count() bytes,
// any storage: segment() uses the label array) while it reads the map for the block means: the
// separate own_states() pass would read the map once more. When the blocks
// tile the map (division's leaves do), `own` equals own_states(grid, params); voxels outside
// every block are not written. The states are not zeroed first: the blocks must tile the map
// (division's leaves do), or the voxels outside every block hold garbage. With `summed` (every
// row of the map added, with `own` and float_bounds() of params), the map is read only for
// blocks off the lattice of cells.
//
// With `growth`, the creation also writes the unknown growth's row masks and occupied-row flags
// (GrowthRows) when the blocks lie on the lattice of cells, and sets growth->filled.
struct GrowthRows;
UninitVector<std::uint8_t> create_segments_and_own_states(const Grid& grid, const std::vector<Block>& blocks,
                                                          const Params& params, std::uint8_t* own,
                                                          CellRows* summed = nullptr,
                                                          GrowthRows* growth = nullptr,
                                                          const kernels::Table& k = kernels::active());

// What the unknown growth packs from the states before it starts, written by the creation as it
// writes the states from its cells' states instead (8 voxels per cell and per byte of a mask
// word, no reading of the states back): for every row, W (state unknown) and C (state free and
// own state unknown) in `scratch` as grow_unknown() keeps them (grow_unknown_scratch_bytes()),
// and its byte of `occupied_rows` (an occupied voxel in the row).
//
// With `defer_states`, the creation leaves the states themselves to the growth, which writes each
// row once from its cells' states and the grown voxels (instead of the creation writing every
// row and the growth rewriting a third of them): `cell_states` then holds every cell's state.
struct GrowthRows {
  std::uint8_t* scratch = nullptr;        // 8-byte aligned, grow_unknown_scratch_bytes()
  const word_t* unknown_bits = nullptr;   // CellRows' bits of the own states' unknown voxels
  std::uint8_t* occupied_rows = nullptr;  // one byte per row (refine() fills it if not)
  bool filled = false;                    // set by the creation when it wrote them
  bool defer_states = false;              // asked by the caller
  // By the creation when it deferred the states: cell (cx, cy, cz) at cx + ncx * (cy + ncy * cz)
  // (ncx, ncy: cells along x and y, kMeanCell voxels each).
  std::vector<std::uint8_t> cell_states;
};
// For tests: the block means as creation sums them when the blocks tile the map on the lattice of
// kMeanCell^3 cells (row by row, into the cells' sums); empty for other blocks.
std::vector<double> block_means_by_rows(const Grid& grid, const std::vector<Block>& blocks, int threads);

// (The refinement and the default rules on these bits: detail::refine() in stages/refine.hpp,
// detail::apply_voxel_rules() in rules/departures.hpp.)

}  // namespace occseg::detail
